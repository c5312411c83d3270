#pragma once
// `liod replay --kitti-raw DRIVE`: a KITTI raw drive's sweeps (point-cloud path, HDL-64E beams,
// times from azimuth) and its 100 Hz OXTS samples as the pipeline's LiDAR and IMU sources, both on
// the pace clock of the other file sources.

#include <atomic>
#include <filesystem>
#include <memory>
#include <string>

#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"

namespace liod {

class KittiLidarSource : public LidarSource {
 public:
  KittiLidarSource(std::filesystem::path drive, std::shared_ptr<const PaceClock> pace);
  void run(LidarOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return "KITTI raw sweeps in " + drive_.string(); }
  std::size_t sweeps_read() const { return read_.load(); }
  std::size_t sweeps_total() const { return total_.load(); }
  /// Returns dropped by the point-cloud path: off every beam of the table, or too near.
  std::size_t returns_dropped() const { return dropped_.load(); }

 private:
  std::filesystem::path drive_;
  std::shared_ptr<const PaceClock> pace_;
  std::atomic<std::size_t> read_{0}, total_{0}, dropped_{0};
};

class KittiImuSource : public ImuSource {
 public:
  KittiImuSource(std::filesystem::path drive, std::shared_ptr<const PaceClock> pace);
  void run(ImuOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return "KITTI OXTS in " + drive_.string(); }

 private:
  std::filesystem::path drive_;
  std::shared_ptr<const PaceClock> pace_;
};

/// The drive's first sweep start and first OXTS time, ns (0 when it has none).
std::int64_t first_kitti_sweep_ns(const std::filesystem::path& drive);
std::int64_t first_kitti_imu_ns(const std::filesystem::path& drive);

}  // namespace liod
