#pragma once
// liod's threads and rings, shared by `liod run`, `liod record` and `liod replay`:
//
//   LiDAR source thread --ScanItem ring--> odometry thread --PoseEvent ring--> publisher thread
//   IMU source thread  ---ImuItem ring--->      |    |                          (pose socket, sinks)
//          |  ^                                 |    +--Keyframe ring--> backend thread
//          |  +------ latest scan update -------+
//          +--------------------- IMU-rate PoseEvent ring ---------------> publisher thread
//
// A source is live (UDP socket, serial port, SocketCAN) or a file (pcap, IMU CSV); either way it
// hands raw packets / samples to LidarOutput / ImuOutput, which own the decoding, time
// correction and ring hand-off, so downstream cannot tell replay from live. LidarOutput also
// extracts each sweep's features (they need the scan alone), so that the odometry thread
// registers scan k while the LiDAR thread prepares scan k+1.
//
// Ordering (what the odometry sees, in which order):
// - Live (`Ordering::Arrival`): IMU samples are fed as they arrive; the IMU thread itself turns
//   each sample into an IMU-rate pose (the last scan update propagated, ImuRatePropagator), so
//   those never wait behind a scan update. A scan is processed as soon as the IMU has reached its end time, or after
//   time.imu_wait_s without it. A scan's pose depends only on the IMU samples up to the first
//   one past its end, so it does not depend on thread timing while the IMU keeps up. When the
//   odometry falls behind (a scan's data waited longer than threads.scan_max_lag_s for it, the
//   scan is older than pose_socket.stale_after_s, and a newer scan is there; not while it works
//   off the start's backlog) it skips to the newest scan, counted; the IMU is fed on, so the filter predicts across the skipped scans as
//   across a LiDAR gap. A pose that reaches the publisher more than pose_socket.stale_after_s
//   after its input arrived is flagged stale, not ok.
// - Replay as fast as possible (`Ordering::Lockstep`): sources run unthrottled and the rings are
//   lossless (producers wait for room), and the odometry consumes in data order exactly like the
//   original single-threaded loop: before a scan, IMU samples up to its end + 20 ms; the scan is
//   processed once the IMU reaches its end (or the IMU log ended); IMU-rate poses are made on the
//   odometry thread in that same order. Same input -> same call sequence -> same poses, every run.

#include <Eigen/Core>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/backend_worker.hpp"
#include "liod/daemon/heartbeat.hpp"
#include "liod/daemon/imu_rate_propagator.hpp"
#include "liod/daemon/pose_protocol.hpp"
#include "liod/daemon/sensor_outputs.hpp"
#include "liod/daemon/state_gate.hpp"
#include "liod/drivers/spsc_ring.hpp"
#include "liod/lidar_inertial_odometry.hpp"
#include "liod/types.hpp"

namespace liod {

/// Per-scan numbers for the scan log (the scan-rate PoseEvent carries them).
struct ScanDiagnostics {
  std::uint32_t status = 0;  ///< OdometryStatus bits
  std::size_t points = 0, edges = 0, planes = 0;
  int residuals = 0, iterations = 0;
  double rms_m = 0, min_eigenvalue = 0, hausdorff_m = -1;
  double deskew_ms = 0, features_ms = 0, registration_ms = 0, map_ms = 0;
  /// The filter's state, body frame: velocity, the LiDAR's correction of the IMU-predicted
  /// velocity, biases, gravity; whether the forward bias and tilt were held.
  Eigen::Vector3d velocity_body = Eigen::Vector3d::Zero(), velocity_correction_body = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero(), gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity_body = Eigen::Vector3d::Zero();
  bool forward_hold = false;
};

struct PoseEvent {
  pose::PoseMessage message;
  ScanDiagnostics diagnostics;        ///< scan poses only
  std::int64_t input_steady_ns = 0;   ///< arrival of the input that produced it (latency)
  std::int64_t queued_ns = 0;         ///< scan poses: of that, waiting in the socket for the driver thread
  std::int64_t process_start_ns = 0;  ///< scan poses: the odometry started on the scan
  std::int64_t process_end_ns = 0;    ///< scan poses: the pose was ready
};

struct KeyframeEvent {
  std::shared_ptr<const Keyframe> keyframe;  // with the filter's pose covariance (keyframe.hpp)
  std::int64_t queued_steady_ns = 0;  ///< when the odometry handed it to the backend
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
class FoxgloveServer;

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
  /// Live sources (Arrival ordering): take steps of the LiDAR's and the IMU's time out
  /// (drivers::ClockStepBridge). Not for file replays: they play a recording as it is.
  bool bridge_clock_steps = false;
  /// Handed to the BackendWorker (tests: a slow backend).
  BackendWorkerOptions backend;
  /// Called on the odometry thread as it starts on each scan (tests: a slow odometry).
  std::function<void(const ScanItem&)> before_scan;
  /// The live view (viewer.foxglove_port; null: off). The threads post copies to it and never
  /// wait for it: the scan only while a viewer subscribes to it.
  std::shared_ptr<FoxgloveServer> viewer;
};

/// Totals for the replay summary (valid after join()).
struct OdometryTotals {
  std::size_t scans = 0, processed = 0, keyframes = 0, degenerate = 0, imu_fed = 0, imu_dropped = 0;
  std::size_t skipped = 0;  ///< live: scans skipped with the odometry behind (threads.scan_max_lag_s)
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

  /// Thread names whose heartbeat is older than `max_age`, or (the backend) whose current unit
  /// of work has run longer than threads.backend_work_limit_s (heartbeat.hpp); empty = healthy.
  /// This is what `liod run` pings systemd's watchdog on.
  std::vector<std::string> stalled(std::chrono::milliseconds max_age) const;
  /// The health JSON (rates since the previous call by the same caller are not kept: counters).
  std::string health_json(HealthRates& rates) const;
  LatencyStats::Summary scan_latency() const { return scan_latency_.summary(); }
  LatencyStats::Summary imu_latency() const { return imu_latency_.summary(); }
  /// The scan latency by stage: in the socket before the driver thread took the packet / in the
  /// ring and waiting for IMU data / odometry / to the socket.
  struct ScanStages {
    LatencyStats::Summary receive, wait, process, publish;
  };
  ScanStages scan_stages() const {
    return {scan_receive_.summary(), scan_wait_.summary(), scan_process_.summary(), scan_publish_.summary()};
  }
  /// The host clock was stepped (run_command's ClockJumpDetector): poses carry kClockJump for
  /// time.jump_flag_s (so they do after a step of the LiDAR's or the IMU's own time).
  void note_host_clock_jump() noexcept;
  /// First error a thread died with ("" if none).
  std::string error() const;

 private:
  void lidar_thread(LidarSource& source);
  void imu_thread(ImuSource* source);
  void odometry_thread();
  struct OdometryLoop;  // the odometry thread's state (pipeline.cpp)
  void feed_imu(OdometryLoop& loop, const ImuItem& item);
  void process_scan(OdometryLoop& loop, ScanItem& item);
  bool lockstep_step(OdometryLoop& loop, bool& done);
  bool arrival_step(OdometryLoop& loop, bool& done);
  /// Live: whether the odometry is behind on the front scan, whose data was complete at
  /// `complete_ns`, and the scan can only come out stale; if so it is skipped (counted, logged
  /// when a run of skips begins).
  bool skip_if_behind(OdometryLoop& loop, std::int64_t complete_ns);
  /// Live: flags `ev` stale (and not ok) when it reaches the publisher at `now` more than
  /// pose_socket.stale_after_s after its input arrived.
  void flag_stale(PoseEvent& ev, std::int64_t now);
  void publisher_thread(PoseServer* server);
  void backend_thread();
  /// One keyframe on the backend thread: its loop search, solve and state files, or shed.
  void backend_unit(const KeyframeEvent& k);
  void apply_thread_config(const ThreadConfig& tc, const char* name);
  void fail(const std::string& what);
  void push_pose(PoseEvent& ev);
  /// Flags from host-time health and clock steps for a pose at `pose_time` (live ordering only:
  /// replay must not depend on thread timing).
  std::uint32_t live_flags(double pose_time) const;
  /// Propagates `item` from the latest anchor into an IMU-rate pose; false before the first anchor.
  /// The map-frame pose of `m` (its odometry-frame pose set): the backend's latest correction
  /// applied, or the odometry pose flagged not_localized without a backend.
  void place_in_map(pose::PoseMessage& m) const;
  bool make_imu_pose(const ImuItem& item, PoseEvent& ev);
  /// Live: the IMU thread's IMU-rate pose for each sample.
  void publish_imu_pose(const ImuItem& item);
  /// pose::kImplausible when a scan's state fails the gate (state_gate.hpp), else 0; logs changes.
  std::uint32_t gate_scan_state(const OdometryResult& result);

  Config config_;
  PipelineOptions options_;
  std::atomic<bool> source_stop_{false};  // sources end; the rest drains
  std::atomic<bool> stop_{false};         // everything ends at its next bounded wait
  drivers::Notifier odometry_wakeup_, publisher_wakeup_, backend_wakeup_;
  drivers::SpscRing<ScanItem> scan_ring_;
  drivers::SpscRing<ImuItem> imu_ring_;
  drivers::SpscRing<PoseEvent> pose_ring_;
  drivers::SpscRing<PoseEvent> imu_pose_ring_;  // live: IMU thread -> publisher
  drivers::SpscRing<KeyframeEvent> keyframe_ring_;
  std::unique_ptr<LidarOutput> lidar_out_;
  std::unique_ptr<ImuOutput> imu_out_;
  std::unique_ptr<BackendWorker> backend_;
  std::unique_ptr<LidarSource> lidar_source_;
  std::unique_ptr<ImuSource> imu_source_;
  ImuRatePropagator propagator_;  // used by one thread: the IMU thread live, the odometry thread in lockstep
  AnchorExchange anchors_;        // live: odometry thread -> IMU thread
  PoseEvent imu_event_;           // the IMU thread's reused event
  double imu_saturated_time_ = -std::numeric_limits<double>::infinity();  // used with propagator_, by its thread
  std::vector<std::function<void(const PoseEvent&)>> sinks_;
  std::vector<std::thread> threads_;
  int thread_count_ = 0;
  std::atomic<int> finished_threads_{0};
  Heartbeat hb_odometry_, hb_publisher_, hb_backend_;
  std::atomic<bool> imu_done_{false};
  OdometryTotals totals_;
  std::atomic<std::uint64_t> scans_processed_{0}, backend_keyframes_{0}, host_jumps_{0}, odometry_imu_dropped_{0};
  std::atomic<std::uint64_t> imu_inconsistent_scans_{0};
  std::atomic<std::int64_t> host_jump_steady_ns_{0};
  std::atomic<double> last_process_ms_{0.0};
  LatencyStats scan_latency_, imu_latency_, scan_receive_, scan_wait_, scan_process_, scan_publish_;
  std::atomic<std::uint64_t> socket_clients_{0}, socket_skipped_{0}, socket_dropped_{0};
  std::atomic<std::uint64_t> imu_poses_withheld_{0};  // past pose_socket.imu_rate_horizon_s
  StateLimits state_limits_;
  bool scan_state_plausible_ = true;                  // odometry thread only
  std::atomic<std::uint64_t> implausible_poses_{0};   // scan and IMU-rate poses flagged implausible
  // The odometry's re-initialisations (reinitialization.hpp): new local maps after an outage,
  // start-ups again from an implausible state.
  std::atomic<std::uint64_t> odometry_new_maps_{0}, odometry_restarts_{0};
  std::atomic<std::uint64_t> scans_skipped_{0};       // live: the odometry behind (threads.scan_max_lag_s)
  std::atomic<std::uint64_t> stale_poses_{0};         // flagged stale (pose_socket.stale_after_s)
  std::atomic<std::uint64_t> backend_shed_{0};        // keyframes the backend skipped, behind
  std::uint64_t backend_shed_logged_ = 0;             // backend thread only
  mutable std::mutex error_mutex_;
  std::string error_;
};

}  // namespace liod
