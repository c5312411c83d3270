#include "liod/daemon/sensor_outputs.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>

#include "liod/drivers/byte_order.hpp"
#include "liod/lidar_inertial_odometry.hpp"

namespace liod {
namespace {

drivers::HeliosOptions helios_options(const Config& config) {
  drivers::HeliosOptions o;
  o.model = config.lidar.model == LidarModel::kHelios16P ? drivers::HeliosModel::Helios16P : drivers::HeliosModel::Helios5515;
  if (!config.lidar.angles_csv.empty()) o.angles = drivers::load_angles_csv(config.lidar.angles_csv);
  o.msop.min_range_m = static_cast<float>(config.lidar.min_range_m);
  o.msop.max_range_m = static_cast<float>(config.lidar.max_range_m);
  o.split_azimuth_deg = config.lidar.split_azimuth_deg;
  o.max_held_packets = static_cast<std::size_t>(config.lidar.packets_before_difop);
  o.calibration_updates = config.lidar.calibration_updates == CalibrationUpdates::kFollow
                              ? drivers::CalibrationUpdates::Follow
                              : drivers::CalibrationUpdates::Pin;
  return o;
}

}  // namespace

std::int64_t steady_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---- LidarOutput -------------------------------------------------------------------------------
LidarOutput::LidarOutput(const Config& config, drivers::SpscRing<ScanItem>& ring, bool lossless, bool bridge_clock_steps,
                         const std::atomic<bool>& stop)
    : config_(config), ring_(ring), lossless_(lossless), stop_(stop),
      offset_(static_cast<std::int64_t>(config.time.offset_window_s * 1e9),
              static_cast<std::int64_t>(config.time.jump_threshold_s * 1e9)),
      extractor_(LidarInertialOdometry::feature_params(config)) {
  if (bridge_clock_steps) bridge_.emplace(static_cast<std::int64_t>(config.time.jump_threshold_s * 1e9));
  decoder_ = std::make_unique<drivers::RsHeliosDecoder>(helios_options(config),
                                                        [this](Scan& scan, const drivers::SweepInfo& info) { on_sweep(scan, info); });
  heartbeat();
}

void LidarOutput::packet(std::span<const std::uint8_t> payload, std::int64_t arrival_ns, std::uint16_t dst_port,
                         std::int64_t queued_ns) {
  packet_steady_ = steady_ns();
  packet_queued_ = queued_ns;
  heartbeat_.store(packet_steady_, std::memory_order_relaxed);
  packets_.fetch_add(1, std::memory_order_relaxed);
  if (tap) tap(payload, arrival_ns, dst_port);
  // A sweep this packet ends takes the time shift of the packets before it (they are the sweep).
  decoder_->feed(payload, arrival_ns);
  // MSOP header time (spec §3: 6-byte BE seconds + 4-byte BE µs at offset 20) against arrival.
  if (payload.size() == 1248 && payload[0] == 0x55 && payload[1] == 0xAA && payload[2] == 0x05 && payload[3] == 0x5A) {
    const std::uint64_t sec = drivers::load_be48(&payload[20]);
    const std::uint32_t usec = drivers::load_be32(&payload[26]);
    if (usec < 1000000 && sec < 4000000000ULL) {
      track_time(static_cast<std::int64_t>(sec) * 1000000000 + static_cast<std::int64_t>(usec) * 1000, arrival_ns);
    }
  }
  const auto s = decoder_->stats();
  lost_.store(s.lost_packets, std::memory_order_relaxed);
  std::lock_guard lock(stats_mutex_);
  stats_copy_ = s;
}

bool LidarOutput::sensor_agrees() const {
  return std::llabs(offset_.offset_ns()) < static_cast<std::int64_t>(config_.time.jump_threshold_s * 1e9);
}

std::int64_t LidarOutput::clock_offset() const {
  const auto& difop = decoder_->last_difop();
  switch (config_.time.lidar_clock) {
    case LidarClock::kSensor:
      return 0;
    case LidarClock::kHost:
      return offset_.offset_ns();
    case LidarClock::kAuto: {
      // The sensor's time when it says it is synced and agrees with the host; before its first
      // DIFOP, when it agrees anyway (both synced, or a recording whose capture times are the
      // header times). The IMU is stamped on the host clock, so a synced sensor that disagrees
      // (its clock jumped, or the host lost sync) would put the scans at the wrong IMU time:
      // its scans are timed on the host clock until it agrees again.
      const bool use_sensor = sensor_agrees() && (!difop.has_value() || difop->time_sync_status != 0);
      return use_sensor ? 0 : offset_.offset_ns();
    }
  }
  return 0;
}

void LidarOutput::track_time(std::int64_t header_ns, std::int64_t arrival_ns) {
  offset_.add(arrival_ns, header_ns);
  jumps_.store(offset_.jumps(), std::memory_order_relaxed);
  const std::int64_t offset = clock_offset();
  offset_used_.store(offset, std::memory_order_relaxed);
  shift_ns_ = offset;
  // Bridged once the first DIFOP has settled which clock the configuration uses: the switch to
  // it is not a step. The bridge sees the time the odometry would, so that an offset that
  // follows a step (host clock) and a sensor that steps both come out continuous.
  if (!bridge_ || !decoder_->last_difop()) return;
  const std::uint64_t before = bridge_->steps();
  bridge_->correct(header_ns + offset, packet_steady_);
  shift_ns_ += bridge_->correction_ns();
  if (bridge_->steps() != before) {
    steps_.store(bridge_->steps(), std::memory_order_relaxed);
    step_correction_.store(bridge_->correction_ns(), std::memory_order_relaxed);
    last_step_time_.store(static_cast<double>(header_ns + shift_ns_) * 1e-9 + config_.extrinsics.lidar_time_offset_s,
                          std::memory_order_relaxed);
    spdlog::warn("LiDAR time stepped by {:.6f} s against the arrival clock; taken out to keep scan times continuous "
                 "(total correction {:.6f} s until restart)",
                 static_cast<double>(bridge_->last_step_ns()) * 1e-9, static_cast<double>(bridge_->correction_ns()) * 1e-9);
  }
}

void LidarOutput::on_sweep(Scan& scan, const drivers::SweepInfo& info) {
  if (info.truncated) {
    // The azimuth did not cross the split for a revolution and more: the points are not where the
    // packets put them (a stuck azimuth) or all in one direction (a stalled motor). The odometry
    // gets no such sweep; the next one it gets says so, and no sweep counts as LiDAR alive.
    truncated_since_last_ = true;
    return;
  }
  const auto& difop = decoder_->last_difop();
  const bool synced = difop.has_value() && difop->time_sync_status != 0;
  synced_.store(synced, std::memory_order_relaxed);
  const std::uint64_t jumps = offset_.jumps();
  item_.clock_jump = (synced && !sensor_agrees()) || jumps != jumps_at_last_sweep_;
  jumps_at_last_sweep_ = jumps;
  item_.sweep_truncated = truncated_since_last_;
  truncated_since_last_ = false;
  item_.calibration_changed = info.calibration_changed;
  if (shift_ns_ != 0) {
    const double o = static_cast<double>(shift_ns_) * 1e-9;
    scan.start_time += o;
    scan.end_time += o;
  }
  using std::swap;
  swap(item_.scan, scan);
  // Feature extraction needs the scan alone, not the state: done here, it runs on this thread
  // while the odometry thread registers the previous scan (about a fifth of a scan's work there).
  const std::int64_t extract_start = steady_ns();
  extractor_.extract(item_.scan, item_.features);
  item_.features_ms = static_cast<double>(steady_ns() - extract_start) * 1e-6;
  item_.ready_steady_ns = packet_steady_;
  item_.queued_ns = packet_queued_;
  sweeps_.fetch_add(1, std::memory_order_relaxed);
  last_sweep_.store(packet_steady_, std::memory_order_relaxed);
  // Exchange with the ring: item_ comes back with a recycled buffer, handed back to the decoder.
  if (lossless_) ring_.push_wait(item_, stop_);
  else ring_.try_push(item_);
  swap(item_.scan, scan);
}

void LidarOutput::sweep(Scan& scan) {
  packet_steady_ = steady_ns();
  packet_queued_ = 0;
  heartbeat_.store(packet_steady_, std::memory_order_relaxed);
  on_sweep(scan, drivers::SweepInfo{});
}

void LidarOutput::finish() {
  decoder_->flush();
  {
    std::lock_guard lock(stats_mutex_);
    stats_copy_ = decoder_->stats();
  }
  ring_.close();
}

drivers::HeliosStats LidarOutput::decoder_stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_copy_;
}

// ---- ImuOutput ---------------------------------------------------------------------------------
ImuOutput::ImuOutput(drivers::SpscRing<ImuItem>& ring, bool lossless, const std::atomic<bool>& stop,
                     std::int64_t step_threshold_ns)
    : ring_(ring), lossless_(lossless), stop_(stop) {
  if (step_threshold_ns > 0) bridge_.emplace(step_threshold_ns);
}

void ImuOutput::sample(const ImuSample& delivered) {
  const std::int64_t now = steady_ns();
  heartbeat_.store(now, std::memory_order_relaxed);
  if (tap) tap(delivered);
  ImuSample s = delivered;
  switch (classify(s, range)) {
    case ImuReading::OutOfRange:
      out_of_range_.fetch_add(1, std::memory_order_relaxed);
      return;
    case ImuReading::Saturated:
      s.flags |= ImuSample::kSaturated;
      saturated_.fetch_add(1, std::memory_order_relaxed);
      break;
    case ImuReading::Valid:
      break;
  }
  if (bridge_) {
    // Bridged without the PPS correction the transport added: that one is meant to move the time.
    const std::int64_t pps = pps_correction_ns.load(std::memory_order_relaxed);
    const std::uint64_t before = bridge_->steps();
    bridge_->correct(std::llround(s.time * 1e9) - pps, now);
    if (bridge_->correction_ns() != 0) s.time += static_cast<double>(bridge_->correction_ns()) * 1e-9;
    if (bridge_->steps() != before) {
      steps_.store(bridge_->steps(), std::memory_order_relaxed);
      step_correction_.store(bridge_->correction_ns(), std::memory_order_relaxed);
      last_step_time_.store(s.time, std::memory_order_relaxed);
      spdlog::warn("IMU time stepped by {:.6f} s against the arrival clock; taken out to keep it continuous "
                   "(total correction {:.6f} s until restart)",
                   static_cast<double>(bridge_->last_step_ns()) * 1e-9, static_cast<double>(bridge_->correction_ns()) * 1e-9);
    }
  }
  // A duplicate, or a step back too small to be told from jitter: the odometry needs order.
  if (s.time <= last_time_) {
    out_of_order_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  last_time_ = s.time;
  item_.sample = s;
  item_.arrival_steady_ns = now;
  if (lossless_) ring_.push_wait(item_, stop_);
  else ring_.try_push(item_);
  samples_.fetch_add(1, std::memory_order_relaxed);
  last_.store(now, std::memory_order_relaxed);
  if (on_sample) on_sample(ImuItem{s, now});
}

}  // namespace liod
