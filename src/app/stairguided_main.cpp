// stairguided: the daemon (skeleton until the runtime lands): validates its config and exits.
#include <cstdio>
#include <string>

#include "stairguide/config/config_loader.hpp"

int main(int argc, char** argv) {
  using namespace stairguide;
  std::string config_path;
  std::string check_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--config" || a == "--check-config") && i + 1 < argc) {
      (a == "--config" ? config_path : check_path) = argv[++i];
    } else {
      std::fprintf(stderr, "stairguided: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  try {
    if (!check_path.empty()) {
      load_config(check_path);
      std::printf("%s: ok\n", check_path.c_str());
      return 0;
    }
    if (config_path.empty()) config_path = default_config_path();
    if (!config_path.empty()) load_config(config_path);
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "stairguided: config error: %s\n", e.what());
    return 3;
  }
  std::fprintf(stderr, "stairguided: the runtime is not built yet\n");
  return 1;
}
