#pragma once
// What a test finds outside itself: the read-only reference data in ../shared, the source tree,
// the programs of this build tree (liod-sim, liod), and what the test does when one is missing.
//
// A test that needs one of them and finds it missing skips, with a message naming what is missing,
// on a developer's checkout without ../shared or with only some targets built. Where the
// environment variable CI is set (to anything but "0" or "false"), the test fails instead: CI
// always has ../shared beside the clone and builds every program, so there a missing one is a
// broken run, never a reason to pass quietly. A capability of the host that CI need not have
// either (root for a vcan interface, systemd's tools) skips everywhere (LIOD_SKIP_UNLESS).
//
// The paths need no GoogleTest (the fuzz seed writer and the benchmarks use them); the macros are
// for tests, which include <gtest/gtest.h>.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

namespace liod::test {

inline std::filesystem::path shared_dir() { return LIOD_SHARED_DIR; }
inline std::filesystem::path robosense_dir() { return shared_dir() / "data" / "robosense"; }
inline std::filesystem::path source_dir() { return LIOD_SOURCE_DIR; }
inline std::filesystem::path binary_dir() { return LIOD_BINARY_DIR; }
/// A program of this build tree (liod-sim, liod, ...), built or not.
inline std::filesystem::path built_program(const std::string& name) { return binary_dir() / "bin" / name; }

/// The build tree whose liod-sim makes the tests' simulated drives and keeps them (test-data/):
/// this one, or the one the environment variable LIOD_TEST_DRIVES names. liod-sim's worlds
/// depend on the compiler that built it: several of its calls draw random numbers in more than one
/// argument, and C++ leaves the order of those draws to the compiler (gcc right to left, clang
/// left to right). scripts/test.sh points the clang sanitizer tree at the gcc Release tree, whose
/// drives are the ones the tests' bounds were set on.
inline std::filesystem::path drive_tree() {
  const char* tree = std::getenv("LIOD_TEST_DRIVES");
  return tree != nullptr && *tree != '\0' ? std::filesystem::path(tree) : binary_dir();
}
/// The liod-sim that makes the tests' drives.
inline std::filesystem::path sim_program() { return drive_tree() / "bin" / "liod-sim"; }

/// True in a CI run (CI set, and not to "0" or "false").
inline bool in_ci() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && *ci != '\0' && std::string_view(ci) != "0" && std::string_view(ci) != "false";
}

}  // namespace liod::test

// Skips the test, or fails it under CI, when the path `required` does not exist; `what` names it
// in the message and `hint` says how to get it.
#define LIOD_REQUIRE_PATH(required, what, hint)                                                     \
  do {                                                                                              \
    const std::filesystem::path liod_required_path_ = (required);                                   \
    if (!std::filesystem::exists(liod_required_path_)) {                                            \
      if (::liod::test::in_ci()) FAIL() << what << " missing at " << liod_required_path_ << " (CI=1)"; \
      GTEST_SKIP() << what << " not found at " << liod_required_path_ << " (" << hint << ")";       \
    }                                                                                               \
  } while (false)

/// A file or folder of the reference data, given as a path under ../shared.
#define LIOD_REQUIRE_SHARED(required) \
  LIOD_REQUIRE_PATH(required, "shared data", "tests that read ../shared skip outside a checkout beside it")

/// A program of this build tree, by name.
#define LIOD_REQUIRE_PROGRAM(name) \
  LIOD_REQUIRE_PATH(::liod::test::built_program(name), name, "build target " name " in this tree")

/// The liod-sim that makes the tests' drives, and the Helios-32 angle table in ../shared it
/// simulates the LiDAR with.
#define LIOD_REQUIRE_SIM()                                                                          \
  LIOD_REQUIRE_PATH(::liod::test::sim_program(), "liod-sim", "build target liod-sim in this tree"); \
  LIOD_REQUIRE_SHARED(::liod::test::robosense_dir() / "helios32_angles.csv")

/// Skips the test where the host lacks a capability that CI need not have either; `why` names it.
#define LIOD_SKIP_UNLESS(condition, why) \
  do {                                   \
    if (!(condition)) GTEST_SKIP() << why; \
  } while (false)
