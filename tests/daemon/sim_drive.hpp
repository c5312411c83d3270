#pragma once
// The simulated drive the pipeline tests use: `liod-sim --route urban --seed 3 --duration 8
// --max-speed 12`, generated once per build tree and shared by the test processes
// (tests/support/simulated_drive.hpp).
#include <gtest/gtest.h>

#include <filesystem>

#include "simulated_drive.hpp"
#include "test_support.hpp"

namespace liod::test {

/// The drive's directory, or null when liod-sim is not built or failed.
inline const std::filesystem::path* sim_drive() {
  static const std::filesystem::path dir =
      cached_drive_dir("pipeline-drive", "--route urban --seed 3 --duration 8 --max-speed 12");
  return dir.empty() ? nullptr : &dir;
}

}  // namespace liod::test

// The drive as `var`: skips without liod-sim or ../shared (fails under CI, see test_env.hpp), fails
// when liod-sim does not make it.
#define LIOD_REQUIRE_SIM_DRIVE(var)                                                              \
  LIOD_REQUIRE_SIM();                                                                            \
  const auto* var = liod::test::sim_drive();                                                     \
  ASSERT_NE(var, nullptr) << "liod-sim failed: see " << (liod::test::drive_tree() / "test-data/pipeline-drive/sim.log")
