#pragma once
// The simulated drive the pipeline tests use: `liod-sim --route urban --seed 3 --duration 8
// --max-speed 12`, generated once per test run into a temporary directory. Skips when liod-sim
// has not been built in this tree.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "test_support.hpp"

namespace liod::test {

inline const std::filesystem::path* sim_drive() {
  static const ScratchDir dir("simdrive");
  static bool tried = false;
  static bool ok = false;
  if (!tried) {
    tried = true;
    const auto sim = binary_dir() / "bin" / "liod-sim";
    if (std::filesystem::exists(sim)) {
      const std::string cmd = "timeout 600 " + sim.string() + " --route urban --seed 3 --duration 8 --max-speed 12 --out " +
                              dir.string() + " > " + (dir / "sim.log").string() + " 2>&1";
      ok = std::system(cmd.c_str()) == 0 && std::filesystem::exists(dir / "lidar.pcap");
    }
  }
  return ok ? &dir.path() : nullptr;
}

}  // namespace liod::test

#define LIOD_REQUIRE_SIM_DRIVE(var)                                                              \
  const auto* var = liod::test::sim_drive();                                                     \
  if (var == nullptr) GTEST_SKIP() << "liod-sim not built in " << LIOD_BINARY_DIR << "/bin (build target liod-sim)"
