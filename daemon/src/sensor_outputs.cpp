#include "liod/daemon/sensor_outputs.hpp"

#include <chrono>

#include "liod/drivers/byte_order.hpp"

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
  return o;
}

}  // namespace

std::int64_t steady_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---- LidarOutput -------------------------------------------------------------------------------
LidarOutput::LidarOutput(const Config& config, drivers::SpscRing<ScanItem>& ring, bool lossless,
                         const std::atomic<bool>& stop)
    : config_(config), ring_(ring), lossless_(lossless), stop_(stop),
      offset_(static_cast<std::int64_t>(config.time.offset_window_s * 1e9),
              static_cast<std::int64_t>(config.time.jump_threshold_s * 1e9)) {
  decoder_ = std::make_unique<drivers::RsHeliosDecoder>(helios_options(config),
                                                        [this](Scan& scan, const drivers::SweepInfo&) { on_sweep(scan); });
  heartbeat();
}

void LidarOutput::packet(std::span<const std::uint8_t> payload, std::int64_t arrival_ns, std::uint16_t dst_port) {
  packet_steady_ = steady_ns();
  heartbeat_.store(packet_steady_, std::memory_order_relaxed);
  packets_.fetch_add(1, std::memory_order_relaxed);
  if (tap) tap(payload, arrival_ns, dst_port);
  // MSOP header time (spec §3: 6-byte BE seconds + 4-byte BE µs at offset 20) against arrival.
  if (payload.size() == 1248 && payload[0] == 0x55 && payload[1] == 0xAA && payload[2] == 0x05 && payload[3] == 0x5A) {
    const std::uint64_t sec = drivers::load_be48(&payload[20]);
    const std::uint32_t usec = drivers::load_be32(&payload[26]);
    if (usec < 1000000 && sec < 4000000000ULL) {
      offset_.add(arrival_ns, static_cast<std::int64_t>(sec) * 1000000000 + static_cast<std::int64_t>(usec) * 1000);
      jumps_.store(offset_.jumps(), std::memory_order_relaxed);
    }
  }
  decoder_->feed(payload, arrival_ns);
  const auto s = decoder_->stats();
  lost_.store(s.lost_packets, std::memory_order_relaxed);
  std::lock_guard lock(stats_mutex_);
  stats_copy_ = s;
}

void LidarOutput::on_sweep(Scan& scan) {
  const auto& difop = decoder_->last_difop();
  const bool synced = difop.has_value() && difop->time_sync_status != 0;
  synced_.store(synced, std::memory_order_relaxed);
  std::int64_t offset = 0;
  switch (config_.time.lidar_clock) {
    case LidarClock::kSensor:
      break;
    case LidarClock::kHost:
      offset = offset_.offset_ns();
      break;
    case LidarClock::kAuto: {
      // The sensor's time when it says it is synced; before its first DIFOP, when it agrees with
      // the host anyway (both synced, or a recording whose capture times are the header times).
      const bool agrees = std::llabs(offset_.offset_ns()) < static_cast<std::int64_t>(config_.time.jump_threshold_s * 1e9);
      const bool use_sensor = difop.has_value() ? synced : agrees;
      offset = use_sensor ? 0 : offset_.offset_ns();
      break;
    }
  }
  offset_used_.store(offset, std::memory_order_relaxed);
  if (offset != 0) {
    const double o = static_cast<double>(offset) * 1e-9;
    scan.start_time += o;
    scan.end_time += o;
  }
  using std::swap;
  swap(item_.scan, scan);
  item_.ready_steady_ns = packet_steady_;
  sweeps_.fetch_add(1, std::memory_order_relaxed);
  last_sweep_.store(packet_steady_, std::memory_order_relaxed);
  // Exchange with the ring: item_ comes back with a recycled buffer, handed back to the decoder.
  if (lossless_) ring_.push_wait(item_, stop_);
  else ring_.try_push(item_);
  swap(item_.scan, scan);
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
void ImuOutput::sample(const ImuSample& s) {
  const std::int64_t now = steady_ns();
  heartbeat_.store(now, std::memory_order_relaxed);
  if (tap) tap(s);
  item_.sample = s;
  item_.arrival_steady_ns = now;
  if (lossless_) ring_.push_wait(item_, stop_);
  else ring_.try_push(item_);
  samples_.fetch_add(1, std::memory_order_relaxed);
  last_.store(now, std::memory_order_relaxed);
  if (on_sample) on_sample(ImuItem{s, now});
}

}  // namespace liod
