#pragma once
// What the driver threads do with what they receive, whichever the source (live or file):
// LidarOutput decodes datagrams into sweeps, puts them on the pipeline's clock and hands them to
// the odometry's ring; ImuOutput does the same for IMU samples.

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>

#include "liod/config.hpp"
#include "liod/curvature_features.hpp"
#include "liod/imu_range.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/drivers/spsc_ring.hpp"
#include "liod/drivers/time_sync.hpp"
#include "liod/types.hpp"

namespace liod {

std::int64_t steady_ns() noexcept;

struct ScanItem {
  Scan scan;
  ScanFeatures features;  ///< extracted on the LiDAR thread, while the odometry registers the scan before
  double features_ms = 0.0;
  std::int64_t ready_steady_ns = 0;  ///< when the driver thread took the packet completing the sweep
  std::int64_t queued_ns = 0;        ///< how long that packet had waited in the socket (live)
  bool clock_jump = false;           ///< the LiDAR clock jumped during the sweep, or is off (pose::kClockJump)
  bool sweep_truncated = false;      ///< sweeps before it were cut at the size cap and not passed on (pose::kSweepTruncated)
  bool calibration_changed = false;  ///< the DIFOP disagreed with its calibration, or it is a new one's first (pose::kCalibrationChanged)
};

/// What a live transport counts below the decoding (socket, serial line, CAN), for health.
struct TransportCounters {
  std::atomic<std::uint64_t> lost{0};     ///< never reached liod: receive-buffer overflow, IMU counter gaps
  std::atomic<std::uint64_t> refused{0};  ///< reached it unusable: other sender, truncated, bad checksum
};

struct ImuItem {
  ImuSample sample;
  std::int64_t arrival_steady_ns = 0;
};

/// What the LiDAR driver thread does with each UDP payload, whichever the source.
class LidarOutput {
 public:
  /// `bridge_clock_steps`: take steps of the header time out (live; see drivers::ClockStepBridge).
  LidarOutput(const Config& config, drivers::SpscRing<ScanItem>& ring, bool lossless, bool bridge_clock_steps,
              const std::atomic<bool>& stop);
  /// One datagram. `arrival_realtime_ns`: kernel receive time (live) or capture time (file);
  /// `queued_ns`: how long it waited in the socket before this thread took it (live, else 0).
  void packet(std::span<const std::uint8_t> payload, std::int64_t arrival_realtime_ns, std::uint16_t dst_port,
              std::int64_t queued_ns = 0);
  /// A finished sweep from the point-cloud path (no packets, no decoder): on the pipeline's clock
  /// already, handed on as a decoded Helios sweep is. The scan is left with a recycled buffer.
  void sweep(Scan& scan);
  /// End of stream: flush the decoder and close the ring.
  void finish();
  void heartbeat() noexcept { heartbeat_.store(steady_ns(), std::memory_order_relaxed); }

  drivers::HeliosStats decoder_stats() const;
  std::int64_t heartbeat_ns() const noexcept { return heartbeat_.load(std::memory_order_relaxed); }
  std::uint64_t packets() const noexcept { return packets_.load(std::memory_order_relaxed); }
  std::uint64_t lost_packets() const noexcept { return lost_.load(std::memory_order_relaxed); }
  std::uint64_t sweeps() const noexcept { return sweeps_.load(std::memory_order_relaxed); }
  std::int64_t last_sweep_steady_ns() const noexcept { return last_sweep_.load(std::memory_order_relaxed); }
  /// Host - LiDAR clock offset in use (0 when the LiDAR's own time is used), and whether the
  /// LiDAR reports GPS/PTP sync.
  std::int64_t clock_offset_ns() const noexcept { return offset_used_.load(std::memory_order_relaxed); }
  bool sensor_synced() const noexcept { return synced_.load(std::memory_order_relaxed); }
  std::uint64_t clock_jumps() const noexcept { return jumps_.load(std::memory_order_relaxed); }
  /// Steps of the LiDAR's time taken out (live only; see drivers::ClockStepBridge), the total
  /// correction, and where the last one was on the pipeline's (IMU) timeline (+inf = never).
  std::uint64_t clock_steps() const noexcept { return steps_.load(std::memory_order_relaxed); }
  std::int64_t step_correction_ns() const noexcept { return step_correction_.load(std::memory_order_relaxed); }
  double last_step_time() const noexcept { return last_step_time_.load(std::memory_order_relaxed); }

  /// Called with every datagram before decoding (liod record).
  std::function<void(std::span<const std::uint8_t>, std::int64_t, std::uint16_t)> tap;
  /// Kept up to date by a live source.
  TransportCounters transport;

 private:
  void on_sweep(Scan& scan, const drivers::SweepInfo& info);
  /// The host - LiDAR offset the configuration's lidar_clock calls for now.
  std::int64_t clock_offset() const;
  /// The LiDAR's header time is within time.jump_threshold_s of the host's.
  bool sensor_agrees() const;
  /// An MSOP header's time: offset tracking and step bridging.
  void track_time(std::int64_t header_ns, std::int64_t arrival_ns);
  const Config& config_;
  drivers::SpscRing<ScanItem>& ring_;
  bool lossless_;
  const std::atomic<bool>& stop_;
  drivers::OffsetTracker offset_;
  std::optional<drivers::ClockStepBridge> bridge_;
  std::int64_t shift_ns_ = 0;  // offset + step correction as of the last packet: added to a sweep it ended
  std::unique_ptr<drivers::RsHeliosDecoder> decoder_;
  FeatureExtractor extractor_;
  ScanItem item_;
  std::int64_t packet_steady_ = 0;
  std::int64_t packet_queued_ = 0;
  mutable std::mutex stats_mutex_;  // decoder stats are copied out for health (once a second)
  drivers::HeliosStats stats_copy_;
  std::atomic<std::int64_t> heartbeat_{0};
  std::atomic<std::uint64_t> packets_{0}, lost_{0}, sweeps_{0}, jumps_{0}, steps_{0};
  std::uint64_t jumps_at_last_sweep_ = 0;
  bool truncated_since_last_ = false;  // sweeps cut at the size cap since the last one passed on
  std::atomic<std::int64_t> last_sweep_{0}, step_correction_{0};
  std::atomic<double> last_step_time_{std::numeric_limits<double>::infinity()};
  std::atomic<std::int64_t> offset_used_{0};
  std::atomic<bool> synced_{false};
};

/// What the IMU driver thread does with each sample, whichever the transport.
class ImuOutput {
 public:
  /// A `step_threshold_ns` > 0 takes steps of the sample times beyond it out (live; see
  /// drivers::ClockStepBridge).
  ImuOutput(drivers::SpscRing<ImuItem>& ring, bool lossless, const std::atomic<bool>& stop, std::int64_t step_threshold_ns);
  void sample(const ImuSample& s);
  void finish() { ring_.close(); }
  void heartbeat() noexcept { heartbeat_.store(steady_ns(), std::memory_order_relaxed); }
  std::int64_t heartbeat_ns() const noexcept { return heartbeat_.load(std::memory_order_relaxed); }
  std::uint64_t samples() const noexcept { return samples_.load(std::memory_order_relaxed); }
  std::int64_t last_sample_steady_ns() const noexcept { return last_.load(std::memory_order_relaxed); }
  /// Samples not passed on because their time was not after the previous one's.
  std::uint64_t out_of_order() const noexcept { return out_of_order_.load(std::memory_order_relaxed); }
  std::uint64_t clock_steps() const noexcept { return steps_.load(std::memory_order_relaxed); }
  std::int64_t step_correction_ns() const noexcept { return step_correction_.load(std::memory_order_relaxed); }
  double last_step_time() const noexcept { return last_step_time_.load(std::memory_order_relaxed); }
  /// Samples with an axis at the IMU's measurement range (flagged ImuSample::kSaturated, passed on)
  /// and beyond it or not finite (dropped).
  std::uint64_t saturated() const noexcept { return saturated_.load(std::memory_order_relaxed); }
  std::uint64_t out_of_range() const noexcept { return out_of_range_.load(std::memory_order_relaxed); }
  /// The IMU's measurement range (imu.gyro_range_rad_s, imu.accel_range_m_s2); set before the thread starts.
  ImuRange range;
  /// Host-clock correction from PPS (added to host-stamped samples by the transports).
  std::atomic<std::int64_t> pps_correction_ns{0};
  /// Called with every sample as the transport delivered it (liod record).
  std::function<void(const ImuSample&)> tap;
  /// Called on the IMU thread with every sample after it went to the ring (IMU-rate poses, live).
  std::function<void(const ImuItem&)> on_sample;
  /// Kept up to date by a live transport.
  TransportCounters transport;

 private:
  drivers::SpscRing<ImuItem>& ring_;
  bool lossless_;
  const std::atomic<bool>& stop_;
  std::optional<drivers::ClockStepBridge> bridge_;
  double last_time_ = -std::numeric_limits<double>::infinity();  // of the last sample passed on
  ImuItem item_;
  std::atomic<std::int64_t> heartbeat_{0};
  std::atomic<std::uint64_t> samples_{0}, steps_{0}, out_of_order_{0}, saturated_{0}, out_of_range_{0};
  std::atomic<std::int64_t> last_{0}, step_correction_{0};
  std::atomic<double> last_step_time_{std::numeric_limits<double>::infinity()};
};

}  // namespace liod
