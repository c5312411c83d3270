#pragma once
// `liod replay`: a recorded drive (LiDAR pcap + IMU CSV log) through the odometry, as fast as
// the CPU allows, writing the trajectory for evaluation.

#include <iosfwd>
#include <string>

#include "liod/config.hpp"

namespace liod {

struct ReplayOptions {
  std::string pcap;
  std::string imu_csv;
  std::string trajectory_tum;      // scan-rate body poses
  std::string imu_rate_tum;        // optional: IMU-rate propagated poses
  std::string scan_log_csv;        // optional: per-scan status, features, timings
  bool progress = false;           // a progress bar on stderr
};

/// Returns the process exit code; prints a summary to `out`.
int run_replay(const Config& config, const ReplayOptions& options, std::ostream& out);

}  // namespace liod
