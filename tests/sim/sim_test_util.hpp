#pragma once
// Shared helpers of the simulator tests: scratch directories, short runs, file reading.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "liod/sim/simulator.hpp"

namespace liod::sim::test {

inline std::string angles_csv() {
  return std::string(LIOD_SHARED_DIR) + "/data/robosense/helios32_angles.csv";
}

inline bool have_shared() { return std::filesystem::exists(angles_csv()); }

#define LIOD_SIM_REQUIRE_SHARED()                                                     \
  do {                                                                                \
    if (!::liod::sim::test::have_shared()) {                                          \
      GTEST_SKIP() << "shared data not found at " << ::liod::sim::test::angles_csv(); \
    }                                                                                 \
  } while (0)

/// A fresh directory under the build tree, removed and recreated.
inline std::string scratch_dir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(LIOD_BINARY_DIR) / "test-sim-tmp" /
                                  (name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline SimConfig short_config(RouteKind route, std::uint64_t seed, double duration,
                              const std::string& out) {
  SimConfig c;
  c.scene.route = route;
  c.scene.seed = seed;
  c.scene.duration = duration;
  c.scene.max_speed = 12.0;
  c.angles_csv = angles_csv();
  c.out_dir = out;
  return c;
}

inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::vector<std::vector<double>> read_numbers(const std::string& path, char sep,
                                                     bool skip_header) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::vector<double>> rows;
  if (skip_header) {
    std::getline(in, line);
  }
  while (std::getline(in, line)) {
    if (line.empty()) {
      continue;
    }
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, sep)) {
      row.push_back(std::stod(cell));
    }
    rows.push_back(row);
  }
  return rows;
}

}  // namespace liod::sim::test
