// synth command: renders a synthetic preset into a dataset folder (with labels.yaml and
// groundtruth.txt) and optionally an .oni recording.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/command.hpp"
#include "stairguide/capture/dataset.hpp"
#include "stairguide/capture/oni.hpp"
#include "stairguide/capture/synth_source.hpp"

namespace stairguide::cli {
namespace {

int synth_cmd(Context& ctx) {
  const bool list = ctx.flag("--list");
  const auto scene = ctx.option("--scene");
  const auto out = ctx.option("--out");
  const auto frames_opt = ctx.int_option("--frames", 1, 1000000);
  const auto seed_opt = ctx.int_option("--seed", 0, 4294967295L);
  const auto oni = ctx.option("--oni");
  ctx.positionals(0, 0);
  if (list) {
    for (const auto* l : {&synth::presets(), &synth::world_presets(), &synth::walk_presets(),
                          &synth::rig_presets(), &synth::world2_presets(), &synth::drop_presets()})
      for (const auto& p : *l)
        std::printf("%-30s %6ld  %s\n", p.name.c_str(), p.default_frames, p.summary.c_str());
    return 0;
  }
  if (!scene) throw UsageError("--scene NAME is required (see --list)");
  if (!out) throw UsageError("--out DIR is required");
  const synth::PresetInfo* preset = synth::find_preset_info(*scene);
  if (!preset) {
    std::string names;
    for (const auto* l : {&synth::presets(), &synth::world_presets(), &synth::walk_presets(),
                          &synth::rig_presets(), &synth::world2_presets(), &synth::drop_presets()})
      for (const auto& p : *l) names += (names.empty() ? "" : ", ") + p.name;
    throw UsageError("unknown scene '" + *scene + "' (known: " + names + ")");
  }
  const long frames = frames_opt ? *frames_opt : preset->default_frames;
  const auto seed = static_cast<std::uint32_t>(seed_opt ? *seed_opt : 1);

  // Nothing already written is lost: refuse a folder that holds files.
  std::error_code ec;
  if (std::filesystem::exists(*out, ec) &&
      (!std::filesystem::is_directory(*out, ec) || !std::filesystem::is_empty(*out, ec))) {
    std::fprintf(stderr, "stairguide synth: %s exists and is not an empty folder; refusing to overwrite it\n",
                 out->c_str());
    return 1;
  }
  if (oni && std::filesystem::exists(*oni, ec)) {
    std::fprintf(stderr, "stairguide synth: %s exists; refusing to overwrite it\n", oni->c_str());
    return 1;
  }

  auto source = synth::make_source(*scene, frames, seed);
  DatasetWriter writer(*out, source->intrinsics());
  std::unique_ptr<OniWriter> oni_writer;
  if (oni) oni_writer = std::make_unique<OniWriter>(*oni, source->intrinsics(), true, ctx.config.capture.fps);
  const bool progress = isatty(STDERR_FILENO) != 0;
  RgbdFrame frame;
  long n = 0;
  for (;; ++n) {
    const ReadResult r = source->read(frame);
    if (r.status == ReadStatus::kEnd) break;
    if (!r.ok()) {
      std::fprintf(stderr, "stairguide synth: %s\n", r.message.c_str());
      return 1;
    }
    const auto truth = source->truth();
    writer.write(frame, truth ? &*truth : nullptr);
    if (oni_writer) oni_writer->write(frame);
    if (progress && (n % 10 == 0 || n + 1 == frames))
      std::fprintf(stderr, "\rsynth %s: frame %ld/%ld", scene->c_str(), n + 1, frames);
  }
  if (progress) std::fprintf(stderr, "\n");
  writer.close();
  if (oni_writer) oni_writer->close();
  std::printf("%s: %ld frames of '%s' (seed %u)%s%s\n", out->c_str(), n, scene->c_str(), seed,
              oni ? ", recording " : "", oni ? oni->c_str() : "");
  return 0;
}

}  // namespace

SG_COMMAND("synth", "synth --scene NAME --out DIR [--frames N] [--seed S] [--oni FILE] | --list",
           "render a synthetic preset into a dataset folder (labels, poses) and optionally an .oni",
           synth_cmd);

}  // namespace stairguide::cli
