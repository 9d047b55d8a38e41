# Run by `cmake --install` (install(SCRIPT) in CMakeLists.txt), after the files are installed:
# writes the copies of the config and the systemd unit that name where this install put things.
# Here CMAKE_INSTALL_PREFIX is the prefix of this install (`--prefix` included) and file(INSTALL)
# adds $ENV{DESTDIR}, so the paths agree whatever the prefix (issue 41, defect 8: installed under
# /usr/local, the config still named /usr/share/stairguide/sounds and the daemon was mute).
#
# Set by the caller (install(CODE)): sg_source_dir, sg_binary_dir, and sg_datadir, sg_bindir,
# sg_unitdir (relative to the prefix, or absolute). The config goes to /etc/stairguide whatever the
# prefix: that is where the daemon and the tool look for it by default.
foreach(v sg_source_dir sg_binary_dir sg_datadir sg_bindir sg_unitdir)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "install_configured.cmake: ${v} is not set")
  endif()
endforeach()

function(sg_full out dir)
  if(IS_ABSOLUTE "${dir}")
    set(${out} "${dir}" PARENT_SCOPE)
  else()
    set(${out} "${CMAKE_INSTALL_PREFIX}/${dir}" PARENT_SCOPE)
  endif()
endfunction()
sg_full(datadir "${sg_datadir}")
sg_full(bindir "${sg_bindir}")
sg_full(unitdir "${sg_unitdir}")
set(sysconfdir "/etc")
set(sounds "${datadir}/stairguide/sounds")
# A folder of this install's own: two installs from one build tree may run at once (tests).
string(RANDOM LENGTH 12 nonce)
set(staging "${sg_binary_dir}/install-configured/${nonce}")
file(MAKE_DIRECTORY "${staging}")

# The config: only the sounds_dir line changes (the key's comment is kept).
file(READ "${sg_source_dir}/config/stairguide.yaml" text)
string(REGEX MATCH "\n  sounds_dir: \"[^\"\n]*\"" found "${text}")
if(NOT found)
  message(FATAL_ERROR "install: no 'sounds_dir: \"...\"' line under feedback: in ${sg_source_dir}/config/stairguide.yaml")
endif()
string(REPLACE "${found}" "\n  sounds_dir: \"${sounds}\"" text "${text}")
file(WRITE "${staging}/stairguide.yaml" "${text}")
file(INSTALL DESTINATION "${sysconfdir}/stairguide" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
     FILES "${staging}/stairguide.yaml")

# The unit: ExecStart is the installed launcher (its --config is /etc/stairguide/stairguide.yaml).
file(READ "${sg_source_dir}/systemd/stairguide.service" unit)
string(REPLACE "/usr/bin/stairguided" "${bindir}/stairguided" unit "${unit}")
file(WRITE "${staging}/stairguide.service" "${unit}")
file(INSTALL DESTINATION "${unitdir}" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
     FILES "${staging}/stairguide.service")
file(REMOVE_RECURSE "${staging}")
