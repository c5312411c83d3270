#include "liod/daemon/kitti_sources.hpp"

#include <cmath>

#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/kitti_raw.hpp"

namespace liod {
KittiLidarSource::KittiLidarSource(std::filesystem::path drive, std::shared_ptr<const PaceClock> pace)
    : drive_(std::move(drive)), pace_(std::move(pace)) {}

void KittiLidarSource::run(LidarOutput& out, const std::atomic<bool>& stop) {
  const auto sweeps = drivers::read_kitti_sweep_list(drive_);
  total_.store(sweeps.size());
  const drivers::CloudScanConfig config = drivers::kitti_cloud_config();
  Scan scan;
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    // A sweep is whole once its last return is in: released at its end time.
    if (!pace_->wait_until(to_ns(sweeps[i].end_s), stop, [&] { out.heartbeat(); })) break;
    drivers::CloudScanStats stats;
    scan = drivers::make_scan(drivers::read_kitti_sweep(sweeps[i], i), config, &stats);
    dropped_.fetch_add(stats.no_beam + stats.too_near);
    out.sweep(scan);
    read_.store(i + 1);
  }
}

KittiImuSource::KittiImuSource(std::filesystem::path drive, std::shared_ptr<const PaceClock> pace)
    : drive_(std::move(drive)), pace_(std::move(pace)) {}

void KittiImuSource::run(ImuOutput& out, const std::atomic<bool>& stop) {
  std::size_t n = 0;
  for (const ImuSample& s : drivers::read_kitti_oxts(drive_)) {
    if (!pace_->wait_until(to_ns(s.time), stop, [&] { out.heartbeat(); })) break;
    out.sample(s);
    if ((++n & 63) == 0) out.heartbeat();
  }
}

std::int64_t first_kitti_sweep_ns(const std::filesystem::path& drive) {
  const auto starts = drivers::read_kitti_timestamps(drive / "velodyne_points" / "timestamps_end.txt");
  return starts.empty() ? 0 : to_ns(starts.front());
}

std::int64_t first_kitti_imu_ns(const std::filesystem::path& drive) {
  const auto times = drivers::read_kitti_timestamps(drive / "oxts" / "timestamps.txt");
  return times.empty() ? 0 : to_ns(times.front());
}

}  // namespace liod
