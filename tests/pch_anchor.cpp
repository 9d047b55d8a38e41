// The translation unit that builds tests/pch.hpp's precompiled header (CMakeLists.txt:
// sg_test_pch); every test binary reuses it.
#include "pch.hpp"
