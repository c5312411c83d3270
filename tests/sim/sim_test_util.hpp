#pragma once
// Shared helpers of the simulator tests: scratch directories, short runs, file reading.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "liod/sim/simulator.hpp"
#include "scratch_dir.hpp"
#include "test_env.hpp"

namespace liod::sim::test {

inline std::string angles_csv() { return (::liod::test::robosense_dir() / "helios32_angles.csv").string(); }

#define LIOD_SIM_REQUIRE_SHARED() LIOD_REQUIRE_SHARED(::liod::sim::test::angles_csv())

/// A fresh, empty directory `name` in the test program's scratch directory.
inline std::string scratch_dir(const std::string& name) {
  const std::filesystem::path p = ::liod::test::program_scratch_dir() / name;
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
