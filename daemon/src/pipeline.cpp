#include "liod/daemon/pipeline.hpp"

#include <pthread.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <sstream>

#include "liod/daemon/extrinsics_check.hpp"
#include "liod/daemon/foxglove_server.hpp"
#include "liod/daemon/pose_server.hpp"

namespace liod {
namespace {

std::uint32_t status_flags(std::uint32_t odometry_status) {
  std::uint32_t f = 0;
  if (odometry_status & kStatusInitializing) f |= pose::kInitializing;
  if (odometry_status & kStatusDegenerate) f |= pose::kDegenerate;
  if (odometry_status & kStatusImuGap) f |= pose::kImuLost;
  if (odometry_status & kStatusKeyframe) f |= pose::kKeyframe;
  if (odometry_status & kStatusFewFeatures) f |= pose::kFewFeatures;
  if (odometry_status & kStatusImuInconsistent) f |= pose::kImuInconsistent;
  return f;
}

std::uint32_t with_ok(std::uint32_t f) {
  constexpr std::uint32_t kBad = pose::kInitializing | pose::kDegenerate | pose::kImuLost | pose::kLidarLost |
                                 pose::kImuInconsistent | pose::kImplausible | pose::kSweepTruncated |
                                 pose::kCalibrationChanged | pose::kImuSaturated | pose::kStale;
  return (f & kBad) == 0 ? f | pose::kOk : f;
}

// What a scan pose passes on to the IMU-rate poses propagated from it: every flag of the scan's
// own that kept it from `ok` (an IMU-rate pose is the scan's state moved on by the IMU, no better
// than it). The host-time flags (IMU or LiDAR lost now, a clock step) each IMU-rate pose gets
// afresh from live_flags.
constexpr std::uint32_t kInheritedFlags = pose::kInitializing | pose::kDegenerate | pose::kFewFeatures |
                                          pose::kImuLost | pose::kImuInconsistent | pose::kImplausible;

void fill_state(pose::PoseMessage& m, const NavState& s) {
  m.time = s.time;
  m.position = s.position;
  m.orientation = Eigen::Quaterniond(s.rotation);  // as the TUM writer always did: bit-identical files
  m.velocity = s.velocity;
}

}  // namespace

// ---- LatencyStats ----------------------------------------------------------------------------
void LatencyStats::add(double us) {
  constexpr std::size_t kWindow = 4096;  // the most recent samples: a rolling figure for health
  std::lock_guard lock(mutex_);
  if (window_.size() < kWindow) {
    window_.push_back(us);
  } else {
    window_[next_] = us;
    next_ = (next_ + 1) % kWindow;
  }
  max_ = std::max(max_, us);
}

LatencyStats::Summary LatencyStats::summary() const {
  std::vector<double> v;
  Summary s;
  {
    std::lock_guard lock(mutex_);
    v = window_;
    s.max_us = max_;
  }
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median_us = v[v.size() / 2];
  s.p99_us = v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(v.size()))) - 1)];
  return s;
}

// ---- Pipeline ----------------------------------------------------------------------------------
Pipeline::Pipeline(const Config& config, PipelineOptions options)
    : config_(config), options_(std::move(options)),
      scan_ring_(static_cast<std::size_t>(config.threads.scan_ring), &odometry_wakeup_),
      imu_ring_(static_cast<std::size_t>(config.threads.imu_ring), &odometry_wakeup_),
      pose_ring_(static_cast<std::size_t>(config.threads.pose_ring), &publisher_wakeup_),
      imu_pose_ring_(static_cast<std::size_t>(config.threads.pose_ring), &publisher_wakeup_),
      keyframe_ring_(static_cast<std::size_t>(config.threads.keyframe_ring), &backend_wakeup_) {
  const bool lossless = options_.ordering == Ordering::Lockstep;
  const bool bridge = options_.bridge_clock_steps && !lossless;  // lockstep has no arrival clock
  lidar_out_ = std::make_unique<LidarOutput>(config_, scan_ring_, lossless, bridge, source_stop_);
  imu_out_ = std::make_unique<ImuOutput>(imu_ring_, lossless, source_stop_,
                                         bridge ? static_cast<std::int64_t>(config_.time.jump_threshold_s * 1e9) : 0);
  imu_out_->range = {config_.imu.gyro_range_rad_s, config_.imu.accel_range_m_s2};
  if (!lossless && options_.imu_rate_poses) imu_out_->on_sample = [this](const ImuItem& item) { publish_imu_pose(item); };
  if (config_.backend.enabled) backend_ = std::make_unique<BackendWorker>(config_, options_.backend);
  state_limits_ = state_limits(config_);
}

Pipeline::~Pipeline() {
  request_stop();
  stop_.store(true);
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
}

void Pipeline::add_sink(std::function<void(const PoseEvent&)> sink) { sinks_.push_back(std::move(sink)); }

void Pipeline::fail(const std::string& what) {
  spdlog::error("{}", what);
  {
    std::lock_guard lock(error_mutex_);
    if (error_.empty()) error_ = what;
  }
  request_stop();
}

std::string Pipeline::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

void Pipeline::apply_thread_config(const ThreadConfig& tc, const char* name) {
  ::pthread_setname_np(::pthread_self(), name);
  if (!options_.realtime_threads) return;
  if (tc.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(tc.cpu, &set);
    if (::pthread_setaffinity_np(::pthread_self(), sizeof set, &set) != 0) {
      spdlog::warn("{}: cannot pin to CPU {} (not present or not allowed); running unpinned", name, tc.cpu);
    }
  }
  if (tc.priority > 0) {
    sched_param p{};
    p.sched_priority = tc.priority;
    if (::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &p) != 0) {
      spdlog::warn("{}: SCHED_FIFO priority {} not permitted (needs an RLIMIT_RTPRIO of at least {}: the unit's "
                   "LimitRTPRIO); normal scheduling",
                   name, tc.priority, tc.priority);
    }
  }
}

void Pipeline::start(std::unique_ptr<LidarSource> lidar, std::unique_ptr<ImuSource> imu) {
  lidar_source_ = std::move(lidar);
  imu_source_ = std::move(imu);
  std::unique_ptr<PoseServer> server;
  if (!options_.pose_socket.empty()) server = std::make_unique<PoseServer>(options_.pose_socket, config_.pose_socket);
  const auto now = steady_ns();
  for (Heartbeat* hb : {&hb_odometry_, &hb_publisher_, &hb_backend_}) hb->beat(now);
  auto wrap = [this](const char* name, auto body) {
    return [this, name, body]() mutable {
      try {
        body();
      } catch (const std::exception& e) {
        fail(std::string(name) + ": " + e.what());
      }
      finished_threads_.fetch_add(1);
    };
  };
  thread_count_ = 5;
  threads_.emplace_back(wrap("lidar", [this] { lidar_thread(*lidar_source_); }));
  threads_.emplace_back(wrap("imu", [this] { imu_thread(imu_source_.get()); }));
  threads_.emplace_back(wrap("odometry", [this] { odometry_thread(); }));
  threads_.emplace_back(wrap("publisher", [this, s = std::shared_ptr<PoseServer>(std::move(server))] { publisher_thread(s.get()); }));
  threads_.emplace_back(wrap("backend", [this] { backend_thread(); }));
}

void Pipeline::join() {
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
}

bool Pipeline::drain(std::chrono::milliseconds limit) {
  request_stop();
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!finished() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const bool clean = finished();
  stop_.store(true);  // whatever is still running now exits at its next bounded wait
  join();
  return clean;
}

void Pipeline::lidar_thread(LidarSource& source) {
  apply_thread_config(config_.threads.lidar, "liod-lidar");
  try {
    source.run(*lidar_out_, source_stop_);
  } catch (...) {
    lidar_out_->finish();
    throw;
  }
  lidar_out_->finish();
}

void Pipeline::imu_thread(ImuSource* source) {
  apply_thread_config(config_.threads.imu, "liod-imu");
  auto finish = [this] {
    imu_out_->finish();
    imu_pose_ring_.close();
  };
  if (source != nullptr) {
    try {
      source->run(*imu_out_, source_stop_);
    } catch (...) {
      finish();
      throw;
    }
  }
  finish();
}

std::uint32_t Pipeline::live_flags(double pose_time) const {
  if (options_.ordering == Ordering::Lockstep) return 0;
  const std::int64_t now = steady_ns();
  const auto imu_lost_ns = static_cast<std::int64_t>(config_.drivers.imu.lost_after_s * 1e9);
  const auto lidar_lost_ns = static_cast<std::int64_t>(config_.drivers.lidar.lost_after_s * 1e9);
  std::uint32_t f = 0;
  if (imu_source_ != nullptr && now - imu_out_->last_sample_steady_ns() > imu_lost_ns) f |= pose::kImuLost;
  if (now - lidar_out_->last_sweep_steady_ns() > lidar_lost_ns) f |= pose::kLidarLost;
  // A sensor's step is placed on the data timeline (a pose processed late is flagged by when its
  // data was taken); the host clock's by when it was seen.
  const double flag_s = config_.time.jump_flag_s;
  auto after_step = [&](double step_time) { return step_time <= pose_time && pose_time < step_time + flag_s; };
  const std::int64_t host_jump = host_jump_steady_ns_.load(std::memory_order_relaxed);
  if (after_step(lidar_out_->last_step_time()) || after_step(imu_out_->last_step_time()) ||
      (host_jump != 0 && now - host_jump < static_cast<std::int64_t>(flag_s * 1e9))) {
    f |= pose::kClockJump;
  }
  return f;
}

void Pipeline::note_host_clock_jump() noexcept {
  host_jumps_.fetch_add(1, std::memory_order_relaxed);
  host_jump_steady_ns_.store(steady_ns(), std::memory_order_relaxed);
}

void Pipeline::place_in_map(pose::PoseMessage& m) const {
  if (!backend_) {
    m.map_position = m.position;
    m.map_orientation = m.orientation;
    m.flags |= pose::kNotLocalized;
    return;
  }
  const MapCorrection c = backend_->correction();
  m.map_position = c.map_from_odom * m.position;
  m.map_orientation = Eigen::Quaterniond(c.map_from_odom.linear()) * m.orientation;
  m.map_orientation.normalize();
  m.correction_sequence = c.sequence;
  if (!c.localized) m.flags |= pose::kNotLocalized;
}

bool Pipeline::make_imu_pose(const ImuItem& item, PoseEvent& ev) {
  if ((item.sample.flags & ImuSample::kSaturated) != 0) imu_saturated_time_ = item.sample.time;
  const auto state = propagator_.add(item.sample);
  if (!state) return false;
  const ScanAnchor& anchor = *propagator_.anchor();
  const double dead_reckoned_s = state->time - anchor.state.time;
  // Dead reckoning drifts with the square of time and more: when the scan updates fall behind
  // (an overloaded CPU, a LiDAR that stopped) the pose stops rather than runs away, and the
  // next pose after the gap starts from a fresh scan update instead of jumping back to it.
  if (dead_reckoned_s > config_.pose_socket.imu_rate_horizon_s) {
    imu_poses_withheld_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  ev.message.type = pose::MessageType::ImuPose;
  fill_state(ev.message, *state);
  ev.message.angular_rate = item.sample.gyro - state->gyro_bias;
  ev.message.covariance = anchor.pose_covariance;  // of the last scan update (not propagated)
  std::uint32_t f = anchor.flags;
  if (dead_reckoned_s > config_.drivers.lidar.lost_after_s) f |= pose::kLidarLost;
  if (imu_saturated_time_ > anchor.state.time) f |= pose::kImuSaturated;  // integrated a clipped sample
  // The anchor's covariance was checked with its scan; what the IMU adds can still overflow.
  if (check_state(*state, state_limits_) != StateFault::kNone) {
    f |= pose::kImplausible;
    implausible_poses_.fetch_add(1, std::memory_order_relaxed);
  }
  ev.message.flags = with_ok(f | live_flags(state->time));
  place_in_map(ev.message);
  ev.input_steady_ns = item.arrival_steady_ns;
  return true;
}

std::uint32_t Pipeline::gate_scan_state(const OdometryResult& result) {
  StateFault fault = check_state(result.state, state_limits_);
  if (fault == StateFault::kNone) fault = check_covariance(result.covariance);
  const bool was_plausible = scan_state_plausible_;
  scan_state_plausible_ = fault == StateFault::kNone;
  if (scan_state_plausible_) {
    if (!was_plausible) spdlog::info("odometry state plausible again at t={:.3f}", result.state.time);
    return 0;
  }
  implausible_poses_.fetch_add(1, std::memory_order_relaxed);
  if (was_plausible) {
    spdlog::error("odometry state implausible at t={:.3f}: {} (speed {:.3g} m/s); poses published without ok",
                  result.state.time, to_string(fault), result.state.velocity.norm());
  }
  return pose::kImplausible;
}

void Pipeline::publish_imu_pose(const ImuItem& item) {
  ScanAnchor anchor;
  if (anchors_.take(anchor)) propagator_.set_anchor(anchor);
  if (make_imu_pose(item, imu_event_)) imu_pose_ring_.try_push(imu_event_);
}

void Pipeline::push_pose(PoseEvent& ev) {
  if (options_.ordering == Ordering::Lockstep) pose_ring_.push_wait(ev, stop_);
  else pose_ring_.try_push(ev);
}

namespace {

// What a scan's result says of its processing, for the scan log.
ScanDiagnostics scan_diagnostics(const OdometryResult& result, double features_ms) {
  ScanDiagnostics d;
  d.status = result.status;
  d.points = result.points;
  d.edges = result.edge_features;
  d.planes = result.plane_features;
  d.residuals = result.residuals;
  d.iterations = result.iterations;
  d.rms_m = result.rms_residual_m;
  d.min_eigenvalue = result.min_translation_eigenvalue;
  d.hausdorff_m = result.hausdorff_m;
  d.deskew_ms = result.deskew_ms;
  d.features_ms = features_ms;
  d.registration_ms = result.registration_ms;
  d.map_ms = result.map_ms;
  const Eigen::Matrix3d world_to_body = result.state.rotation.transpose();
  d.velocity_body = world_to_body * result.state.velocity;
  d.velocity_correction_body = result.velocity_correction_body;
  d.accel_bias = result.state.accel_bias;
  d.gyro_bias = result.state.gyro_bias;
  d.gravity_body = world_to_body * result.state.gravity;
  d.forward_hold = result.forward_hold;
  return d;
}

}  // namespace

// The odometry thread's state between its steps.
struct Pipeline::OdometryLoop {
  explicit OdometryLoop(const Config& config) : odometry(config, state_limits(config)) {}
  LidarInertialOdometry odometry;
  bool lockstep = false;
  bool imu_poses = false;
  std::int64_t imu_wait_ns = 0;
  std::deque<ScanItem> pending;
  ScanItem spare;
  ImuItem held;
  bool have_held = false;
  Eigen::Vector3d last_gyro = Eigen::Vector3d::Zero();
  PoseEvent imu_event;
  // Data times of the last clipped IMU sample fed and of the last scan pose: a scan whose interval
  // held a clipped sample was predicted and deskewed with it.
  double last_saturated = -std::numeric_limits<double>::infinity();
  double previous_scan_time = -std::numeric_limits<double>::infinity();
  // Live skipping (arrival_step): the arrival of the last IMU sample fed, the lag bound, the
  // flags of skipped sweeps that the next scan pose carries, whether the filter has started (a
  // pose past initializing) and since kept up (no scan waiting), and whether skips are under way.
  std::int64_t imu_arrival_ns = 0;
  std::int64_t max_lag_ns = 0;
  std::uint32_t carried_flags = 0;
  std::unique_ptr<ExtrinsicsCheck> extrinsics_check;  // null: odometry.extrinsics_check_s is 0
  bool started = false;
  bool kept_up = false;
  bool skipping = false;
  void retire_front() {
    spare = std::move(pending.front());
    pending.pop_front();
  }
};

void Pipeline::feed_imu(OdometryLoop& loop, const ImuItem& item) {
  loop.odometry.add_imu(item.sample);
  if (loop.extrinsics_check) loop.extrinsics_check->add_imu(item.sample);
  ++totals_.imu_fed;
  odometry_imu_dropped_.store(loop.odometry.dropped_imu_samples(), std::memory_order_relaxed);
  loop.last_gyro = item.sample.gyro;
  loop.imu_arrival_ns = item.arrival_steady_ns;
  if ((item.sample.flags & ImuSample::kSaturated) != 0) loop.last_saturated = item.sample.time;
  // Live, the IMU thread makes the IMU-rate poses (publish_imu_pose).
  if (loop.lockstep && loop.imu_poses && make_imu_pose(item, loop.imu_event)) push_pose(loop.imu_event);
}

void Pipeline::process_scan(OdometryLoop& loop, ScanItem& item) {
  const std::int64_t start_ns = steady_ns();
  hb_odometry_.beat(start_ns);
  if (options_.before_scan) options_.before_scan(item);
  const auto result = loop.odometry.process(item.scan, item.features);
  odometry_new_maps_.store(loop.odometry.new_maps(), std::memory_order_relaxed);
  odometry_restarts_.store(loop.odometry.restarts(), std::memory_order_relaxed);
  ++totals_.scans;
  if (!result) return;
  ++totals_.processed;
  scans_processed_.fetch_add(1, std::memory_order_relaxed);
  if ((result->status & (kStatusInitializing | kStatusSpeedUnknown)) == 0) loop.started = true;
  const double ms = result->deskew_ms + item.features_ms + result->registration_ms;
  totals_.front_end_ms.push_back(ms);
  last_process_ms_.store(ms + result->map_ms, std::memory_order_relaxed);
  if (result->status & kStatusDegenerate) ++totals_.degenerate;
  if (result->status & kStatusImuInconsistent) imu_inconsistent_scans_.fetch_add(1, std::memory_order_relaxed);
  if (result->status & kStatusKeyframe) ++totals_.keyframes;
  PoseEvent ev;
  ev.message.type = pose::MessageType::ScanPose;
  fill_state(ev.message, result->state);
  ev.message.angular_rate = loop.last_gyro - result->state.gyro_bias;
  ev.message.covariance = pose::pose_covariance_from_state(result->covariance);
  const std::uint32_t scan_flags = status_flags(result->status) | gate_scan_state(*result);
  std::uint32_t f = scan_flags | live_flags(result->state.time);
  f &= ~static_cast<std::uint32_t>(pose::kLidarLost);  // this pose comes from a scan
  if (item.clock_jump) f |= pose::kClockJump;
  if (item.sweep_truncated) f |= pose::kSweepTruncated;
  if (item.calibration_changed) f |= pose::kCalibrationChanged;
  f |= loop.carried_flags;  // from sweeps skipped since the last scan pose
  loop.carried_flags = 0;
  if (loop.last_saturated > loop.previous_scan_time) f |= pose::kImuSaturated;
  loop.previous_scan_time = result->state.time;
  if (loop.extrinsics_check && loop.extrinsics_check->add_scan(result->state.time, result->state.rotation,
                                                               result->state.position, f)) {
    f |= pose::kExtrinsicsSuspect;
  }
  ev.message.flags = with_ok(f);
  place_in_map(ev.message);
  ev.diagnostics = scan_diagnostics(*result, item.features_ms);
  ev.input_steady_ns = item.ready_steady_ns - item.queued_ns;
  ev.queued_ns = item.queued_ns;
  ev.process_start_ns = start_ns;
  ev.process_end_ns = steady_ns();
  push_pose(ev);
  if (options_.viewer && options_.viewer->wants_scans()) {
    options_.viewer->post_scan({std::make_shared<const Scan>(item.scan), result->state, ev.message.angular_rate});
  }
  if (loop.imu_poses && !(result->status & kStatusSpeedUnknown)) {
    // IMU-rate poses are as (un)reliable as the scan they start from: while it is initialising
    // they are flagged so; before any speed is known (the first scan) there are none: dead
    // reckoning at zero speed from a rolling start would run away.
    const ScanAnchor anchor{result->state, loop.odometry.gravity(), ev.message.covariance,
                            (scan_flags & kInheritedFlags) | (f & (pose::kSweepTruncated | pose::kCalibrationChanged | pose::kExtrinsicsSuspect))};
    if (loop.lockstep) propagator_.set_anchor(anchor);
    else anchors_.publish(anchor);
  }
  if ((result->status & kStatusKeyframe) && !loop.odometry.keyframes().empty()) {
    KeyframeEvent k{std::make_shared<const Keyframe>(loop.odometry.keyframes().back()), steady_ns()};
    if (options_.viewer) {
      std::vector<std::uint64_t> window;
      for (const Keyframe& w : loop.odometry.keyframes()) window.push_back(w.id);
      options_.viewer->post_keyframe(k.keyframe, std::move(window));
    }
    if (loop.lockstep) keyframe_ring_.push_wait(k, stop_);
    else keyframe_ring_.try_push(k);
  }
}

// Replay as fast as possible: each scan once the IMU has reached its end, deterministically.
// Returns whether anything moved; `done` once the scans have run out.
bool Pipeline::lockstep_step(OdometryLoop& loop, bool& done) {
  bool progress = false;
  if (loop.pending.empty() && scan_ring_.try_pop(loop.spare)) {
    loop.pending.push_back(std::move(loop.spare));
    progress = true;
  }
  if (loop.pending.empty()) {
    done = scan_ring_.drained();  // like the single-threaded replay, IMU samples after the last scan are not used
    return progress;
  }
  const double end = loop.odometry.scan_end_time(loop.pending.front().scan);
  for (;;) {
    if (!loop.have_held) loop.have_held = imu_ring_.try_pop(loop.held);
    if (!loop.have_held || loop.held.sample.time > end + 0.02) break;
    feed_imu(loop, loop.held);
    loop.have_held = false;
    progress = true;
  }
  const bool imu_ended = !loop.have_held && imu_ring_.drained();
  // A held sample is past the scan's end: an IMU gap left nothing up to the end, and waiting for
  // it would block both sources for good. Process now (flagged IMU gap).
  const bool imu_passed = loop.have_held && loop.held.sample.time > end;
  if (loop.odometry.latest_imu_time() >= end || imu_passed || imu_ended) {
    process_scan(loop, loop.pending.front());
    loop.retire_front();
    progress = true;
  }
  return progress;
}

// Live (and paced replay): scans as they arrive, each once the IMU has reached its end or it has
// waited time.imu_wait_s for it.
bool Pipeline::arrival_step(OdometryLoop& loop, bool& done) {
  bool progress = false;
  while (loop.pending.size() < scan_ring_.capacity() && scan_ring_.try_pop(loop.spare)) {
    loop.pending.push_back(std::move(loop.spare));
    progress = true;
  }
  auto process_ready = [&]() {
    while (!loop.pending.empty()) {
      const ScanItem& front = loop.pending.front();
      const double end = loop.odometry.scan_end_time(front.scan);
      const bool imu_there = loop.odometry.latest_imu_time() >= end;
      const bool waited = steady_ns() - front.ready_steady_ns > loop.imu_wait_ns;
      if (!imu_there && !waited && !imu_ring_.drained()) break;
      // When the scan's data was all there: the sweep, and the IMU up to its end (the sample
      // that took it there is the last one fed, or an earlier one: then this is later than the
      // truth and the lag found shorter), or the end of its wait for the IMU. A late IMU is
      // the IMU's delay, not the odometry's, and never makes it skip.
      const std::int64_t complete = imu_there ? std::max(front.ready_steady_ns, loop.imu_arrival_ns)
                                              : front.ready_steady_ns + loop.imu_wait_ns;
      if (!skip_if_behind(loop, complete)) process_scan(loop, loop.pending.front());
      loop.retire_front();
      progress = true;
    }
  };
  process_ready();
  while (imu_ring_.try_pop(loop.held)) {
    feed_imu(loop, loop.held);
    progress = true;
    process_ready();
  }
  done = loop.pending.empty() && scan_ring_.drained() && imu_ring_.drained();
  return progress;
}

// A scan that can only come out stale (older than pose_socket.stale_after_s already), with a
// newer scan there, is skipped when the odometry is what holds it up: its data (sweep, and IMU up
// to its end) has waited longer than threads.scan_max_lag_s for it. Working through the backlog
// instead, a slow odometry (a loaded CPU, a large map update) publishes ever older poses, 16 scans
// deep with the ring full. A one-off slow scan (the start-up search registers the scans it held in
// one call: 0.22 s on the test drive) leaves a backlog younger than the stale bound, worked off
// scan by scan; a late IMU alone (the scans wait for it) never skips, or a steady IMU delay beyond
// the bound would skip every scan but the newest. The IMU is fed on, so the next scan is predicted
// across a skipped one as across a LiDAR gap, and the flags of what happened in its sweep pass
// to the next scan pose. Nothing is skipped before the odometry has kept up once after the
// filter started: the first scans of a process cost the most (page faults, the first map, the
// start-up search registering its held scans at once: 0.65 s in a fresh `liod run` on the test
// machine, loaded), their poses are initializing (no controller uses them), and that backlog is
// worked off once.
bool Pipeline::skip_if_behind(OdometryLoop& loop, std::int64_t complete_ns) {
  const std::int64_t now = steady_ns();
  const ScanItem& front = loop.pending.front();
  const bool newer = loop.pending.size() > 1 || scan_ring_.front() != nullptr;
  const double age_s = static_cast<double>(now - (front.ready_steady_ns - front.queued_ns)) * 1e-9;
  if (!newer && loop.started) loop.kept_up = true;  // nothing waits behind this scan
  if (!newer && loop.skipping) {
    spdlog::info("odometry caught up: {} scans skipped so far", scans_skipped_.load());
    loop.skipping = false;
  }
  if (!loop.kept_up || !newer || now - complete_ns <= loop.max_lag_ns || age_s <= config_.pose_socket.stale_after_s) {
    return false;
  }
  if (front.clock_jump) loop.carried_flags |= pose::kClockJump;
  if (front.sweep_truncated) loop.carried_flags |= pose::kSweepTruncated;
  if (front.calibration_changed) loop.carried_flags |= pose::kCalibrationChanged;
  scans_skipped_.fetch_add(1, std::memory_order_relaxed);
  if (!loop.skipping) {
    spdlog::warn("odometry behind: the scan ending at t={:.3f} waited {:.0f} ms for it and arrived {:.0f} ms ago "
                 "(threads.scan_max_lag_s {} s, pose_socket.stale_after_s {} s); skipping to the newest scan",
                 loop.odometry.scan_end_time(front.scan), static_cast<double>(now - complete_ns) * 1e-6, age_s * 1e3,
                 config_.threads.scan_max_lag_s, config_.pose_socket.stale_after_s);
    loop.skipping = true;
  }
  return true;
}

void Pipeline::odometry_thread() {
  apply_thread_config(config_.threads.odometry, "liod-odometry");
  OdometryLoop loop(config_);
  loop.lockstep = options_.ordering == Ordering::Lockstep;
  loop.imu_poses = options_.imu_rate_poses;
  loop.imu_wait_ns = static_cast<std::int64_t>(config_.time.imu_wait_s * 1e9);
  loop.max_lag_ns = static_cast<std::int64_t>(config_.threads.scan_max_lag_s * 1e9);
  if (config_.odometry.extrinsics_check_s > 0.0) {
    ExtrinsicsCheckConfig check;
    check.window_s = config_.odometry.extrinsics_check_s;
    check.up_axis = config_.odometry.up_axis;
    // A replay in lockstep gives the same poses on every run: the check runs in line there.
    check.background = !loop.lockstep;
    loop.extrinsics_check = std::make_unique<ExtrinsicsCheck>(config_.extrinsics, check);
  }
  while (!stop_.load(std::memory_order_relaxed)) {
    hb_odometry_.beat(steady_ns());
    bool done = false;
    const bool progress = loop.lockstep ? lockstep_step(loop, done) : arrival_step(loop, done);
    if (done) break;
    if (!progress) odometry_wakeup_.wait(std::chrono::milliseconds(loop.lockstep ? 1 : 5));
  }
  totals_.imu_dropped = loop.odometry.dropped_imu_samples();
  totals_.skipped = scans_skipped_.load();
  pose_ring_.close();
  keyframe_ring_.close();
}

void Pipeline::publisher_thread(PoseServer* server) {
  apply_thread_config(config_.threads.publisher, "liod-publisher");
  std::vector<pollfd> fds;
  PoseEvent ev;
  const auto health_period = std::chrono::duration<double>(config_.pose_socket.health_interval_s);
  auto next_health = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(health_period);
  auto next_housekeeping = std::chrono::steady_clock::now();
  HealthRates rates, viewer_rates;
  FoxgloveServer* viewer = options_.viewer.get();
  auto next_viewer_health = std::chrono::steady_clock::now();
  while (!stop_.load(std::memory_order_relaxed)) {
    hb_publisher_.beat(steady_ns());
    fds.clear();
    fds.push_back({publisher_wakeup_.fd(), POLLIN, 0});
    if (server != nullptr) server->fill_pollfds(fds);
    ::poll(fds.data(), fds.size(), 50);
    if ((fds[0].revents & POLLIN) != 0) publisher_wakeup_.clear();
    if (server != nullptr) server->handle(fds, 1);
    // Scan poses first: each ring is in order, and neither may wait for the other.
    while (pose_ring_.try_pop(ev) || imu_pose_ring_.try_pop(ev)) {
      flag_stale(ev, steady_ns());
      for (const auto& sink : sinks_) sink(ev);
      const bool scan = ev.message.type == pose::MessageType::ScanPose;
      if (server != nullptr) server->broadcast(ev.message);
      if (viewer != nullptr && scan) viewer->post_pose(ev.message);
      if (ev.input_steady_ns > 0) {
        const std::int64_t written = steady_ns();
        (scan ? scan_latency_ : imu_latency_).add(static_cast<double>(written - ev.input_steady_ns) * 1e-3);
        if (scan) {
          scan_receive_.add(static_cast<double>(ev.queued_ns) * 1e-3);
          scan_wait_.add(static_cast<double>(ev.process_start_ns - ev.input_steady_ns - ev.queued_ns) * 1e-3);
          scan_process_.add(static_cast<double>(ev.process_end_ns - ev.process_start_ns) * 1e-3);
          scan_publish_.add(static_cast<double>(written - ev.process_end_ns) * 1e-3);
        }
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (server != nullptr && now >= next_housekeeping) {
      server->housekeeping();
      next_housekeeping = now + std::chrono::milliseconds(100);
      const auto& s = server->stats();
      socket_clients_.store(s.clients, std::memory_order_relaxed);
      socket_skipped_.store(s.skipped_messages, std::memory_order_relaxed);
      socket_dropped_.store(s.dropped_stuck, std::memory_order_relaxed);
    }
    if (server != nullptr && now >= next_health) {
      server->broadcast_health(health_json(rates));
      next_health = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(health_period);
    }
    if (viewer != nullptr && now >= next_viewer_health) {
      viewer->post_health(health_json(viewer_rates));
      next_viewer_health = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(health_period);
    }
    if (pose_ring_.drained() && imu_pose_ring_.drained()) break;
  }
}

// A pose is right for its `time`, but a controller uses the newest one as the present: published
// this late it is off by whatever the vehicle did meanwhile. The replay in lockstep has no arrival
// clock (and must not depend on thread timing).
void Pipeline::flag_stale(PoseEvent& ev, std::int64_t now) {
  if (options_.ordering == Ordering::Lockstep || ev.input_steady_ns <= 0) return;
  if (static_cast<double>(now - ev.input_steady_ns) * 1e-9 <= config_.pose_socket.stale_after_s) return;
  ev.message.flags = (ev.message.flags | pose::kStale) & ~static_cast<std::uint32_t>(pose::kOk);
  stale_poses_.fetch_add(1, std::memory_order_relaxed);
}

void Pipeline::backend_thread() {
  ::pthread_setname_np(::pthread_self(), "liod-backend");
  if (options_.realtime_threads) {
    // Low priority: below the drivers and the odometry, which may preempt it at any time.
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), config_.threads.backend_nice);
  }
  KeyframeEvent k;
  while (!stop_.load(std::memory_order_relaxed)) {
    hb_backend_.beat(steady_ns());
    bool any = false;
    while (keyframe_ring_.try_pop(k)) {
      // Keyframes in ring order: the same sequence on every lockstep replay (deterministic).
      backend_unit(k);
      k.keyframe.reset();
      any = true;
    }
    if (keyframe_ring_.drained()) break;
    if (!any) backend_wakeup_.wait(std::chrono::milliseconds(100));
  }
  if (backend_) {
    hb_backend_.begin_work(steady_ns());
    backend_->finish();
    hb_backend_.end_work(steady_ns());
  }
}

void Pipeline::backend_unit(const KeyframeEvent& k) {
  backend_keyframes_.fetch_add(1, std::memory_order_relaxed);
  if (!backend_) return;
  const std::int64_t start = steady_ns();
  const double waited_s = static_cast<double>(start - k.queued_steady_ns) * 1e-9;
  // Live, a keyframe that waited this long means the backend fell behind (a loop check or solve
  // slower than the keyframes come, a slow disk): it is skipped, loop check and all, so that the
  // backend works on the present rather than on a growing backlog. The graph stays one chain: the
  // next keyframe's odometry factor spans the skipped ones. Replay in lockstep waits instead.
  if (options_.ordering != Ordering::Lockstep && waited_s > config_.threads.backend_max_lag_s) {
    if (backend_shed_.fetch_add(1, std::memory_order_relaxed) == backend_shed_logged_) {
      spdlog::warn("backend behind: keyframe {} waited {:.1f} s (threads.backend_max_lag_s {} s); skipping keyframes "
                   "until it catches up",
                   k.keyframe->id, waited_s, config_.threads.backend_max_lag_s);
    }
    return;
  }
  const std::uint64_t shed = backend_shed_.load(std::memory_order_relaxed);
  if (shed != backend_shed_logged_) {
    spdlog::info("backend caught up: {} keyframes skipped without a loop check so far", shed);
    backend_shed_logged_ = shed;
  }
  hb_backend_.begin_work(start);
  backend_->process(*k.keyframe);
  hb_backend_.end_work(steady_ns());
  if (options_.viewer) {
    // On the backend thread, between keyframes: the graph is not changing under this read.
    const Backend& b = backend_->backend();
    ViewGraph g;
    for (const auto& pose : b.optimized_keyframe_poses()) g.keyframes.push_back(pose.translation());
    for (const LoopCheck& c : b.loop_checks()) {
      if (c.outcome == LoopOutcome::kAccepted) g.loops.emplace_back(c.current, c.candidate);
    }
    options_.viewer->post_graph(std::move(g));
  }
}

std::vector<std::string> Pipeline::stalled(std::chrono::milliseconds max_age) const {
  std::vector<std::string> out;
  const std::int64_t now = steady_ns();
  const std::int64_t limit = std::chrono::duration_cast<std::chrono::nanoseconds>(max_age).count();
  auto check = [&](const char* name, std::int64_t hb) {
    if (now - hb > limit) out.emplace_back(name);
  };
  check("lidar", lidar_out_->heartbeat_ns());
  if (imu_source_) check("imu", imu_out_->heartbeat_ns());
  if (hb_odometry_.stalled(now, limit, limit)) out.emplace_back("odometry");
  if (hb_publisher_.stalled(now, limit, limit)) out.emplace_back("publisher");
  const auto work_limit = static_cast<std::int64_t>(config_.threads.backend_work_limit_s * 1e9);
  if (hb_backend_.stalled(now, limit, work_limit)) out.emplace_back("backend");
  if (!error().empty()) out.emplace_back("error: " + error());
  return out;
}

std::string Pipeline::health_json(HealthRates& rates) const {
  const double now = static_cast<double>(steady_ns()) * 1e-9;
  const auto hs = lidar_out_->decoder_stats();
  const double dt = rates.time > 0 ? now - rates.time : 0.0;
  const std::uint64_t packets = lidar_out_->packets();
  const std::uint64_t imu = imu_out_->samples();
  const std::uint64_t scans = scans_processed_.load();
  auto rate = [&](std::uint64_t n, std::uint64_t prev) { return dt > 0 ? static_cast<double>(n - prev) / dt : 0.0; };
  std::ostringstream j;
  j.setf(std::ios::fixed);
  j.precision(3);
  auto ring = [&](const char* name, auto& r) {
    j << '"' << name << "\":{\"fill\":" << r.size() << ",\"capacity\":" << r.capacity() << ",\"drops\":" << r.drops() << '}';
  };
  auto latency = [&](const char* name, const LatencyStats& stats) {
    const auto l = stats.summary();
    j << '"' << name << "\":{\"median\":" << l.median_us << ",\"p99\":" << l.p99_us << ",\"max\":" << l.max_us << '}';
  };
  j << "{\"version\":1,\"lidar\":{\"packets\":" << packets << ",\"packet_rate_hz\":" << rate(packets, rates.packets)
    << ",\"sweeps\":" << lidar_out_->sweeps() << ",\"lost_packets\":" << hs.lost_packets << ",\"rejected_packets\":"
    << hs.rejected() << ",\"transport_lost\":" << lidar_out_->transport.lost.load() << ",\"transport_refused\":"
    << lidar_out_->transport.refused.load() << ",\"held_before_difop\":" << hs.held_for_calibration << ",\"clock_offset_s\":" << static_cast<double>(lidar_out_->clock_offset_ns()) * 1e-9
    << ",\"sensor_synced\":" << (lidar_out_->sensor_synced() ? "true" : "false") << ",\"clock_jumps\":"
    << lidar_out_->clock_jumps() << ",\"truncated_sweeps\":" << hs.truncated_sweeps << ",\"calibration_changes\":"
    << hs.calibration_changes << "},\"time\":{\"host_clock_jumps\":" << host_jumps_.load()
    << ",\"lidar_steps\":" << lidar_out_->clock_steps()
    << ",\"lidar_step_correction_s\":" << static_cast<double>(lidar_out_->step_correction_ns()) * 1e-9
    << ",\"imu_steps\":" << imu_out_->clock_steps()
    << ",\"imu_step_correction_s\":" << static_cast<double>(imu_out_->step_correction_ns()) * 1e-9
    << "},\"imu\":{\"samples\":" << imu << ",\"rate_hz\":" << rate(imu, rates.imu)
    << ",\"transport_lost\":" << imu_out_->transport.lost.load() << ",\"transport_refused\":"
    << imu_out_->transport.refused.load() << ",\"out_of_order\":" << imu_out_->out_of_order()
    << ",\"saturated\":" << imu_out_->saturated() << ",\"out_of_range\":" << imu_out_->out_of_range()
    << ",\"odometry_dropped\":" << odometry_imu_dropped_.load() << ",\"pps_correction_s\":" << static_cast<double>(imu_out_->pps_correction_ns.load()) * 1e-9
    << "},\"odometry\":{\"scans\":" << scans << ",\"scan_rate_hz\":" << rate(scans, rates.scans)
    << ",\"last_process_ms\":" << last_process_ms_.load() << ",\"imu_poses_withheld\":" << imu_poses_withheld_.load()
    << ",\"imu_inconsistent_scans\":" << imu_inconsistent_scans_.load()
    << ",\"scans_skipped\":" << scans_skipped_.load() << ",\"stale_poses\":" << stale_poses_.load()
    << ",\"implausible_poses\":" << implausible_poses_.load() << ",\"new_maps\":" << odometry_new_maps_.load()
    << ",\"restarts\":" << odometry_restarts_.load()
    << "},\"rings\":{";
  ring("scan", scan_ring_);
  j << ',';
  ring("imu", imu_ring_);
  j << ',';
  ring("pose", pose_ring_);
  j << ',';
  ring("imu_pose", imu_pose_ring_);
  j << ',';
  ring("keyframe", keyframe_ring_);
  j << "},\"latency_us\":{";
  latency("scan_to_socket", scan_latency_);
  j << ',';
  latency("scan_receive", scan_receive_);
  j << ',';
  latency("scan_wait", scan_wait_);
  j << ',';
  latency("scan_process", scan_process_);
  j << ',';
  latency("scan_publish", scan_publish_);
  j << ',';
  latency("imu_to_socket", imu_latency_);
  j << "},\"socket\":{\"clients\":" << socket_clients_.load() << ",\"skipped_messages\":"
    << socket_skipped_.load() << ",\"dropped_clients\":" << socket_dropped_.load()
    << "},\"backend\":{\"keyframes\":" << backend_keyframes_.load() << ",\"keyframes_shed\":" << backend_shed_.load()
    << ",\"busy_s\":" << hb_backend_.busy_s(steady_ns()) << "}}";
  rates.time = now;
  rates.packets = packets;
  rates.imu = imu;
  rates.scans = scans;
  return j.str();
}

}  // namespace liod
