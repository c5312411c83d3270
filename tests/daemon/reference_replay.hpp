#pragma once
// What the pipeline tests compare against: the simulated drive replayed as fast as possible
// (deterministic), computed once per test run, and the files' readers.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/replay.hpp"
#include "test_support.hpp"

namespace liod::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline Config drive_config(const std::filesystem::path& drive) {
  return load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml", (drive / "extrinsics.yaml").string()});
}

struct TumPose {
  double t, x, y, z, qx, qy, qz, qw;
};
inline std::vector<TumPose> read_tum(const std::filesystem::path& p) {
  std::vector<TumPose> out;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    TumPose q{};
    s >> q.t >> q.x >> q.y >> q.z >> q.qx >> q.qy >> q.qz >> q.qw;
    out.push_back(q);
  }
  return out;
}

/// The reference: a replay as fast as possible (computed once).
inline const std::filesystem::path& reference_replay(const std::filesystem::path& drive) {
  static const test::ScratchDir dir("reference");
  static bool done = false;
  if (!done) {
    done = true;
    ReplayOptions o;
    o.pcap = (drive / "lidar.pcap").string();
    o.imu_csv = (drive / "imu.csv").string();
    o.trajectory_tum = (dir / "scan.tum").string();
    o.imu_rate_tum = (dir / "imu.tum").string();
    std::ostringstream out;
    if (run_replay(drive_config(drive), o, out) != 0) ADD_FAILURE() << out.str();
  }
  return dir.path();
}

}  // namespace liod::test
