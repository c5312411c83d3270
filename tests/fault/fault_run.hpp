#pragma once
// A faulted copy of the test drive through the real pipeline (threads, rings, odometry,
// publisher), ordered as `liod replay` orders it, with every published pose collected in the
// order the pose socket would send it.

#include <string>
#include <vector>

#include "fault_drive.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_protocol.hpp"

namespace liod::test {

struct FaultRun {
  std::vector<std::string> applied;        ///< what each fault changed (liod-fault's lines)
  std::vector<pose::PoseMessage> poses;    ///< scan- and IMU-rate poses, in publish order
  OdometryTotals totals;
  drivers::HeliosStats lidar;
  std::uint64_t lidar_refused = 0;         ///< datagrams from a sender other than the LiDAR
  std::uint64_t imu_saturated = 0;         ///< IMU samples at the range (flagged), and beyond it (dropped)
  std::uint64_t imu_out_of_range = 0;
  bool finished = false;                   ///< every thread ended by itself within the time limit
  std::string error;                       ///< the first error a pipeline thread died with

  [[nodiscard]] std::vector<pose::PoseMessage> of_type(pose::MessageType type) const;
};

/// Applies `faults` (liod-fault's text form, seeds 1, 2, ...) to the drive, replays the result as
/// fast as possible and returns what was published.
FaultRun run_with_faults(const FaultDrive& drive, const std::vector<std::string>& faults);

}  // namespace liod::test
