#pragma once
// liod's threads and rings, shared by `liod run`, `liod record` and `liod replay`:
//
//   LiDAR source thread --ScanItem ring--> odometry thread --PoseEvent ring--> publisher thread
//   IMU source thread  ---ImuItem ring--->      |                               (pose socket, sinks)
//                                               +--Keyframe ring--> backend thread (stub: counts)
//
// A source is live (UDP socket, serial port, SocketCAN) or a file (pcap, IMU CSV); either way it
// hands raw packets / samples to LidarOutput / ImuOutput, which own the decoding, time
// correction and ring hand-off, so downstream cannot tell replay from live.
//
// Ordering (what the odometry sees, in which order):
// - Live (`Ordering::Arrival`): IMU samples are fed as they arrive (IMU-rate poses go out at
//   once); a scan is processed as soon as the IMU has reached its end time, or after
//   time.imu_wait_s without it. A scan's pose depends only on the IMU samples up to the first
//   one past its end, so it does not depend on thread timing while the IMU keeps up.
// - Replay as fast as possible (`Ordering::Lockstep`): sources run unthrottled and the rings are
//   lossless (producers wait for room), and the odometry consumes in data order exactly like the
//   original single-threaded loop: before a scan, IMU samples up to its end + 20 ms; the scan is
//   processed once the IMU reaches its end (or the IMU log ended). Same input -> same call
//   sequence -> same poses, every run.

#include <Eigen/Core>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/backend_worker.hpp"
#include "liod/daemon/pose_protocol.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/drivers/spsc_ring.hpp"
#include "liod/drivers/time_sync.hpp"
#include "liod/lidar_inertial_odometry.hpp"
#include "liod/types.hpp"

namespace liod {

std::int64_t steady_ns() noexcept;

struct ScanItem {
  Scan scan;
  std::int64_t ready_steady_ns = 0;  ///< when the packet completing the sweep arrived
  bool clock_jump = false;           ///< the LiDAR clock jumped during the sweep, or is off (pose::kClockJump)
};

struct ImuItem {
  ImuSample sample;
  std::int64_t arrival_steady_ns = 0;
};

/// Per-scan numbers for the scan log (the scan-rate PoseEvent carries them).
struct ScanDiagnostics {
  std::uint32_t status = 0;  ///< OdometryStatus bits
  std::size_t points = 0, edges = 0, planes = 0;
  int residuals = 0, iterations = 0;
  double rms_m = 0, min_eigenvalue = 0, hausdorff_m = -1;
  double deskew_ms = 0, features_ms = 0, registration_ms = 0, map_ms = 0;
};

struct PoseEvent {
  pose::PoseMessage message;
  ScanDiagnostics diagnostics;        ///< scan poses only
  std::int64_t input_steady_ns = 0;   ///< arrival of the input that produced it (latency)
};

struct KeyframeEvent {
  std::shared_ptr<const Keyframe> keyframe;
  StateCovariance covariance = StateCovariance::Zero();
};

enum class Ordering { Arrival, Lockstep };

/// Latency samples (µs) kept by one thread, summarised on request.
class LatencyStats {
 public:
  void add(double us);
  struct Summary {
    std::size_t count = 0;
    double median_us = 0, p99_us = 0, max_us = 0;
  };
  Summary summary() const;

 private:
  mutable std::mutex mutex_;  // taken for ~100 ns per sample, by the publisher and the health reader
  std::vector<double> window_;
  std::size_t next_ = 0;
  double max_ = 0;
};

/// What the LiDAR driver thread does with each UDP payload, whichever the source.
class LidarOutput {
 public:
  LidarOutput(const Config& config, drivers::SpscRing<ScanItem>& ring, bool lossless, const std::atomic<bool>& stop);
  /// One datagram. `arrival_realtime_ns`: kernel receive time (live) or capture time (file).
  void packet(std::span<const std::uint8_t> payload, std::int64_t arrival_realtime_ns, std::uint16_t dst_port);
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

  /// Called with every datagram before decoding (liod record).
  std::function<void(std::span<const std::uint8_t>, std::int64_t, std::uint16_t)> tap;

 private:
  void on_sweep(Scan& scan);
  const Config& config_;
  drivers::SpscRing<ScanItem>& ring_;
  bool lossless_;
  const std::atomic<bool>& stop_;
  drivers::OffsetTracker offset_;
  std::unique_ptr<drivers::RsHeliosDecoder> decoder_;
  ScanItem item_;
  std::int64_t packet_steady_ = 0;
  mutable std::mutex stats_mutex_;  // decoder stats are copied out for health (once a second)
  drivers::HeliosStats stats_copy_;
  std::atomic<std::int64_t> heartbeat_{0};
  std::atomic<std::uint64_t> packets_{0}, lost_{0}, sweeps_{0}, jumps_{0};
  std::uint64_t jumps_at_last_sweep_ = 0;
  std::atomic<std::int64_t> last_sweep_{0};
  std::atomic<std::int64_t> offset_used_{0};
  std::atomic<bool> synced_{false};
};

/// What the IMU driver thread does with each sample, whichever the transport.
class ImuOutput {
 public:
  ImuOutput(drivers::SpscRing<ImuItem>& ring, bool lossless, const std::atomic<bool>& stop)
      : ring_(ring), lossless_(lossless), stop_(stop) {}
  void sample(const ImuSample& s);
  void finish() { ring_.close(); }
  void heartbeat() noexcept { heartbeat_.store(steady_ns(), std::memory_order_relaxed); }
  std::int64_t heartbeat_ns() const noexcept { return heartbeat_.load(std::memory_order_relaxed); }
  std::uint64_t samples() const noexcept { return samples_.load(std::memory_order_relaxed); }
  std::int64_t last_sample_steady_ns() const noexcept { return last_.load(std::memory_order_relaxed); }
  /// Host-clock correction from PPS (added to host-stamped samples by the transports).
  std::atomic<std::int64_t> pps_correction_ns{0};
  std::function<void(const ImuSample&)> tap;

 private:
  drivers::SpscRing<ImuItem>& ring_;
  bool lossless_;
  const std::atomic<bool>& stop_;
  ImuItem item_;
  std::atomic<std::int64_t> heartbeat_{0};
  std::atomic<std::uint64_t> samples_{0};
  std::atomic<std::int64_t> last_{0};
};

class LidarSource {
 public:
  virtual ~LidarSource() = default;
  /// Runs until the stream ends or `stop`; must call out.heartbeat() at least every 100 ms and
  /// must not call out.finish() (the pipeline does).
  virtual void run(LidarOutput& out, const std::atomic<bool>& stop) = 0;
  virtual std::string describe() const = 0;
};

class ImuSource {
 public:
  virtual ~ImuSource() = default;
  virtual void run(ImuOutput& out, const std::atomic<bool>& stop) = 0;
  virtual std::string describe() const = 0;
};

class PoseServer;

/// Counters of the previous health report (to turn counts into rates).
struct HealthRates {
  double time = 0;
  std::uint64_t packets = 0, imu = 0, scans = 0;
};

struct PipelineOptions {
  Ordering ordering = Ordering::Arrival;
  bool imu_rate_poses = true;     ///< compute and publish IMU-rate poses
  std::string pose_socket;        ///< "" = no socket
  bool realtime_threads = true;   ///< apply threads.* priorities/affinity
};

/// Totals for the replay summary (valid after join()).
struct OdometryTotals {
  std::size_t scans = 0, processed = 0, keyframes = 0, degenerate = 0, imu_fed = 0, imu_dropped = 0;
  std::vector<double> front_end_ms;
};

class Pipeline {
 public:
  Pipeline(const Config& config, PipelineOptions options);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Called on the publisher thread for every pose event, in order (before the socket).
  void add_sink(std::function<void(const PoseEvent&)> sink);
  /// Starts all threads. `imu` may be null (no IMU: the odometry then produces no pose).
  void start(std::unique_ptr<LidarSource> lidar, std::unique_ptr<ImuSource> imu);
  /// True once every thread finished by itself (the sources ended and all was drained).
  bool finished() const noexcept { return finished_threads_.load() >= thread_count_; }
  /// Asks the sources to stop; the other threads then drain the rings and end by themselves.
  void request_stop() noexcept { source_stop_.store(true); }
  /// request_stop(), waits up to `limit` for everything to drain, then stops whatever is left
  /// and joins. Returns true when all drained in time.
  bool drain(std::chrono::milliseconds limit);
  void join();

  LidarOutput& lidar_output() { return *lidar_out_; }
  ImuOutput& imu_output() { return *imu_out_; }
  const OdometryTotals& totals() const { return totals_; }
  std::uint64_t keyframes_received() const noexcept { return backend_keyframes_.load(); }
  /// The backend's work (null unless backend.enabled): correction() from any thread; the
  /// algorithm's results (backend()) once the threads have been joined.
  BackendWorker* backend() { return backend_.get(); }

  /// Thread names whose heartbeat is older than `max_age`; empty = healthy.
  std::vector<std::string> stalled(std::chrono::milliseconds max_age) const;
  /// The health JSON (rates since the previous call by the same caller are not kept: counters).
  std::string health_json(HealthRates& rates) const;
  LatencyStats::Summary scan_latency() const { return scan_latency_.summary(); }
  LatencyStats::Summary imu_latency() const { return imu_latency_.summary(); }
  /// First error a thread died with ("" if none).
  std::string error() const;

 private:
  void lidar_thread(LidarSource& source);
  void imu_thread(ImuSource* source);
  void odometry_thread();
  void publisher_thread(PoseServer* server);
  void backend_thread();
  void apply_thread_config(const ThreadConfig& tc, const char* name);
  void fail(const std::string& what);
  void push_pose(PoseEvent& ev);

  Config config_;
  PipelineOptions options_;
  std::atomic<bool> source_stop_{false};  // sources end; the rest drains
  std::atomic<bool> stop_{false};         // everything ends at its next bounded wait
  drivers::Notifier odometry_wakeup_, publisher_wakeup_, backend_wakeup_;
  drivers::SpscRing<ScanItem> scan_ring_;
  drivers::SpscRing<ImuItem> imu_ring_;
  drivers::SpscRing<PoseEvent> pose_ring_;
  drivers::SpscRing<KeyframeEvent> keyframe_ring_;
  std::unique_ptr<LidarOutput> lidar_out_;
  std::unique_ptr<ImuOutput> imu_out_;
  std::unique_ptr<BackendWorker> backend_;
  std::unique_ptr<LidarSource> lidar_source_;
  std::unique_ptr<ImuSource> imu_source_;
  std::vector<std::function<void(const PoseEvent&)>> sinks_;
  std::vector<std::thread> threads_;
  int thread_count_ = 0;
  std::atomic<int> finished_threads_{0};
  std::atomic<std::int64_t> hb_odometry_{0}, hb_publisher_{0}, hb_backend_{0};
  std::atomic<bool> imu_done_{false};
  OdometryTotals totals_;
  std::atomic<std::uint64_t> scans_processed_{0}, backend_keyframes_{0};
  std::atomic<double> last_process_ms_{0.0};
  LatencyStats scan_latency_, imu_latency_, queue_latency_;
  std::atomic<std::uint64_t> socket_clients_{0}, socket_skipped_{0}, socket_dropped_{0};
  mutable std::mutex error_mutex_;
  std::string error_;
};

}  // namespace liod
