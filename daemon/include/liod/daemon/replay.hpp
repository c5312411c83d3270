#pragma once
// `liod replay`: a recorded drive (LiDAR pcap + IMU CSV log, a KITTI raw drive, or a ROS bag) through the same pipeline as
// `liod run` (threads, rings, odometry, publisher), with file sources in place of the sockets.
// As fast as possible (default) it is deterministic: the same poses on every run. `--pace`
// replays at a multiple of the recorded pace (1 = as recorded) with live ordering.

#include <iosfwd>
#include <string>

#include "liod/config.hpp"

namespace liod {

struct ReplayOptions {
  std::string pcap;
  std::string imu_csv;
  /// A KITTI raw drive's folder instead of pcap + IMU log (kitti_sources.hpp); its
  /// calib_imu_to_velo.txt replaces the configuration's extrinsics.
  std::string kitti_raw;
  /// A ROS 1 bag or an MCAP file instead of pcap + IMU log (bag_sources.hpp): its PointCloud2
  /// and Imu topics; the extrinsics are the configuration's.
  std::string bag;
  std::string lidar_topic;
  std::string imu_topic;
  std::string trajectory_tum;      // scan-rate body poses
  std::string imu_rate_tum;        // optional: IMU-rate propagated poses
  std::string map_frame_tum;       // optional: scan-rate map-frame poses as published (localised ones)
  std::string scan_log_csv;        // optional: per-scan status, features, timings
  bool progress = false;           // a progress bar on stderr
  double pace = 0.0;               // 0 = as fast as possible; 1 = recorded pace
  std::string pose_socket;         // optional: also serve poses on this Unix socket
  int foxglove_port = 0;           // optional: the live view on this port (0: viewer.foxglove_port)
};

/// Returns the process exit code; prints a summary to `out`.
int run_replay(const Config& config, const ReplayOptions& options, std::ostream& out);

}  // namespace liod
