#pragma once
// IMU-rate poses without waiting for the scan update: the state of the last scan update (the
// anchor) propagated with every IMU sample since. Live, the IMU thread owns a propagator and
// picks up each new anchor from an AnchorExchange the odometry thread publishes to, so a sample
// becomes a pose within microseconds even while a scan update is running; replay as fast as
// possible feeds one on the odometry thread in data order (deterministic).

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

#include "liod/imu_preintegration.hpp"
#include "liod/types.hpp"

namespace liod {

/// What a scan update leaves for the IMU-rate poses.
struct ScanAnchor {
  NavState state;                 ///< at the scan's end time
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< world frame, as the odometry uses it
  Eigen::Matrix<double, 6, 6> pose_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  std::uint32_t flags = 0;        ///< pose::Flag bits that IMU-rate poses inherit (those that kept the scan pose from ok)
};

class ImuRatePropagator {
 public:
  /// A new scan update: the samples already buffered after its time are integrated onto it at
  /// once (no output for them: they were published from the previous anchor).
  void set_anchor(const ScanAnchor& anchor);
  /// Returns the state at the sample's time, or nullopt before the first anchor or for a sample
  /// not newer than both the anchor and the previous sample.
  std::optional<NavState> add(const ImuSample& sample);
  const std::optional<ScanAnchor>& anchor() const noexcept { return anchor_; }

 private:
  void step(const ImuSample& next);
  std::optional<ScanAnchor> anchor_;
  std::deque<ImuSample> history_;  // from the sample before the anchor's time on (bounded)
  NavState state_;                 // the anchor propagated up to last_
  ImuSample last_;                 // the measurement at state_.time
};

/// The latest anchor, handed from the odometry thread to the IMU thread. The mutex is held
/// only to copy one ScanAnchor (never during a scan update); the reader checks an atomic
/// generation first and locks only when something new is there (~10 times a second).
class AnchorExchange {
 public:
  void publish(const ScanAnchor& anchor);
  /// Copies the anchor into `out` if it changed since the last take(); returns whether it did.
  bool take(ScanAnchor& out);

 private:
  std::mutex mutex_;
  ScanAnchor anchor_;
  std::atomic<std::uint64_t> generation_{0};
  std::uint64_t taken_ = 0;  // reader side only
};

}  // namespace liod
