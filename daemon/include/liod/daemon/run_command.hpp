#pragma once
// `liod run` (the live daemon), `liod record` (the same, plus a capture of what the drivers
// receive) and `liod pose` (a pose socket client that prints).

#include <iosfwd>
#include <string>

#include "liod/config.hpp"

namespace liod {

struct RunOptions {
  std::string record_dir;  ///< non-empty: write lidar.pcap + imu.csv here (liod record)
  double max_seconds = 0;  ///< > 0: stop after this long (tests, benchmarks)
};

/// Runs until SIGTERM/SIGINT (then drains, flushes and returns 0) or a fatal thread error (1).
/// Talks to systemd (READY, STATUS, WATCHDOG, STOPPING) when started by it.
int run_daemon(const Config& config, const RunOptions& options);

/// How `liod pose` prints: `text` (one line a pose, the default), `json` (the server's text mode,
/// docs/pose-protocol.md), `csv` (a header, then one row a pose, every number exact) or `tum`
/// (`t x y z qx qy qz qw`, scan-rate poses only: a trajectory file, as `liod replay --trajectory`).
enum class PoseFormat { Text, Json, Csv, Tum };

struct PoseCommandOptions {
  std::string socket;
  PoseFormat format = PoseFormat::Text;
  bool scan_only = false;
  bool health = false;       ///< also print health messages
  bool map_frame = false;    ///< tum: the map-frame poses instead of the odometry frame's
  long count = 0;            ///< stop after this many poses (0 = until the daemon goes away)
  double timeout_s = 5.0;    ///< give up after this long without a message
};
int run_pose_client(const PoseCommandOptions& options, std::ostream& out);

}  // namespace liod
