#include "liod/lidar_inertial_odometry.hpp"

#include <chrono>
#include <cmath>

#include "liod/beam_calibration_update.hpp"
#include "liod/so3.hpp"
#include "liod/unit_configs.hpp"

namespace liod {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// While the speed is this uncertain (m/s, 1 sigma), a scan's deskew rests on a guess: a rolling
// start's first scans are deskewed again with the LiDAR's speed, and the map is started afresh
// once the speed is known to this.
constexpr double kTrustedVelocityStd = 0.3;
// The IMU kept at most, back from its newest sample.
constexpr double kImuHistory_s = 60.0;
// ...and back from the state's time: the next scan starts there.
constexpr double kImuBeforeState_s = 0.5;
// From this keyframe on each plane query is its voxel's flattest candidate (deskew_features).
// Against the first keyframes' map, with a rolling start's speed still settling, the first
// candidate holds the speed better (docs/design.md, "The flattest plane query per voxel").
constexpr std::size_t kFlattestQueriesFromKeyframe = 3;
// The backend's IMU factor spans the stretch between two keyframes. Over a longer one (a long
// standstill) the preintegration is dead reckoning whose covariance leaves the graph little to
// learn, and its samples would pile up: the keyframe then carries none.
constexpr double kKeyframeImuSpan_s = 10.0;

double velocity_std(const StateCovariance& p) { return std::sqrt(p.block<3, 3>(6, 6).diagonal().maxCoeff()); }

}  // namespace

FeatureParams LidarInertialOdometry::feature_params(const FrontEndConfig& config) { return liod::feature_params(config); }

LidarInertialOdometry::LidarInertialOdometry(const FrontEndConfig& config, const StateLimits& limits)
    : config_(config),
      extrinsics_(config.extrinsics),
      lidar_to_imu_{config.extrinsics.lidar_to_imu_rotation, config.extrinsics.lidar_to_imu_translation},
      noise_(imu_noise(config.imu)),
      update_params_(update_params(config)),
      extractor_(feature_params(config)),
      imu_(kImuHistory_s, config.imu.gyro_range_rad_s, config.imu.accel_range_m_s2),
      start_up_(start_up_config(config)),
      holds_(bias_hold_config(config.odometry)),
      move_off_(move_off_config(config.odometry)),
      window_(keyframe_window_config(config.odometry, update_params_)),
      reinit_(reinitialization_config(config.odometry, limits)) {
  deskew_params_.map_min_point_spacing_m = config.odometry.map_min_point_spacing_m;
  deskew_params_.plane_voxel_m = config.odometry.plane_voxel_m;
  deskew_params_.edge_voxel_m = config.odometry.edge_voxel_m;
}

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan) { return process(scan, nullptr); }

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan, const ScanFeatures& extracted) {
  return process(scan, &extracted);
}

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan, const ScanFeatures* extracted) {
  if (scan.points.empty() || imu_.empty()) return std::nullopt;
  if (!initialized_) {
    OdometryResult result;
    result.points = scan.points.size();
    initialize(scan, result);
    if (!initialized_) return std::nullopt;
    // Report the attitude only; the pose follows once the speed is known.
    result.state = state_;
    result.covariance = covariance_;
    result.status |= kStatusSpeedUnknown;
    return result;
  }
  if (start_up_.searching()) {
    auto result = search_start(scan, extracted);
    if (result) check_recovery(*result);
    return result;
  }
  if (!(scan_end_time(scan) > state_.time)) return std::nullopt;  // a scan from the past (clock jump)
  OdometryResult result;
  result.points = scan.points.size();
  process_scan(scan, extracted, result);
  check_recovery(result);
  return result;
}

void LidarInertialOdometry::initialize(const Scan& scan, OdometryResult& result) {
  // After an implausible state the start-up resumes from the last plausible one.
  if (!start_up_.begin(scan, imu_, state_, covariance_, reinit_.anchor())) return;
  reinit_.resumed();
  if (config_.odometry.beam_calibration && beam_calibration_.beams() != scan.beam_count) {
    BeamCalibrationParams params;
    params.learn_ranges = config_.odometry.beam_range_calibration;
    beam_calibration_ = BeamCalibration(scan.beam_count, params);
  }
  initialized_ = true;
  result.status |= kStatusInitializing;
}

std::optional<OdometryResult> LidarInertialOdometry::search_start(const Scan& scan, const ScanFeatures* extracted) {
  const double end = scan_end_time(scan);
  if (!(end > start_up_.held_until())) {
    // The LiDAR's clock stepped back. Only the attitude has been reported: start afresh from
    // this scan rather than wait (perhaps for hours) for the old time to come round again.
    start_up_.abandon();
    initialized_ = false;
    return process(scan, extracted);
  }
  const std::optional<StartDecision> decision = start_up_.add_scan(scan, imu_, state_);
  if (!decision) return std::nullopt;  // no pose until the speed is known
  if (decision->speed) holds_.hold_forward(start_up_.start_at_speed(*decision->speed, state_, covariance_));
  const bool standstill = decision->standstill();
  move_off_.begin(standstill, state_.position);
  if (standstill) start_up_.settle_at_rest(*decision, end, imu_, state_, covariance_);
  // The IMU carries the state to the scan before this one, which becomes the first keyframe. Not
  // through all of the held scans: with the speed this uncertain, their map pulls the speed
  // towards a standstill scan by scan. A standstill, whose map pulls the right way, is registered
  // from the first scan on: the IMU alone over the wait, its gyro bias taken from a body that
  // may have rocked, would tilt the first keyframe.
  for (std::size_t i = standstill ? 0 : decision->held.size() - 1; i < decision->held.size(); ++i) {
    OdometryResult unreported;  // the first keyframe, and the standstill's scans before this one
    process_scan(decision->held[i], nullptr, unreported);
  }
  OdometryResult result;
  result.points = scan.points.size();
  result.status |= kStatusInitializing;
  process_scan(scan, extracted, result);
  return result;
}

// The pipeline, one scan: numbered steps, each in a unit of its own.
void LidarInertialOdometry::process_scan(const Scan& scan, const ScanFeatures* extracted, OdometryResult& result) {
  // 1. Predict the scan's end state with the IMU (preintegration) and the body's poses through
  //    the sweep (imu_buffer.hpp bridges the IMU's gaps).
  auto t = Clock::now();
  Prediction prediction = predict(scan, result);
  restart_map_if_lost(prediction);
  result.deskew_ms = elapsed_ms(t);

  // 2. Features: the scan's edges and planes by distance-adaptive curvature (unless extracted
  //    already), deskewed to the scan's end (deskew.hpp).
  if (extracted == nullptr) {
    t = Clock::now();
    extractor_.extract(scan, scan_features_);
    result.features_ms = elapsed_ms(t);
  }
  const ScanFeatures& indices = extracted != nullptr ? *extracted : scan_features_;
  t = Clock::now();
  DeskewedFeatures features = deskew(scan, indices, prediction.relative);
  result.deskew_ms += elapsed_ms(t);
  result.edge_features = features.edges.size();
  result.plane_features = features.planes.size();

  // 3. Register the scan on the local map: the iterated update (iterated_update.hpp) under the
  //    bias holds (bias_holds.hpp). The first scan has no map: the prediction stands.
  t = Clock::now();
  if (window_.plane_map().empty()) {
    state_ = prediction.predicted;
    covariance_ = prediction.covariance;
  } else {
    register_scan(scan, indices, prediction, features, result);
  }
  result.registration_ms = elapsed_ms(t);
  if (prediction.preintegration.duration() > 0.0) {
    last_angular_rate_ = so3::log(prediction.start.rotation.transpose() * state_.rotation) / prediction.preintegration.duration();
  }

  // 4. Map: the beams' calibration, the keyframe gate and the window (keyframe_window.hpp).
  t = Clock::now();
  keep_keyframe_imu(prediction, result.status);
  update_map(features, result);
  result.map_ms = elapsed_ms(t);

  imu_.forget_before(state_.time - kImuBeforeState_s);
  result.state = state_;
  result.covariance = covariance_;
}

LidarInertialOdometry::Prediction LidarInertialOdometry::predict(const Scan& scan, OdometryResult& result,
                                                                 ImuUse use) const {
  const double t_end = scan_end_time(scan);
  const NavState start = state_;
  auto intervals = imu_intervals(imu_.samples(), start.time, t_end);
  const auto gaps = use == ImuUse::kBridgeWholeScan ? std::vector<TimeSpan>{{start.time, t_end}}
                                                    : imu_.gaps(start.time, t_end, config_.imu.max_gap_s);
  if (!gaps.empty()) {
    if (use == ImuUse::kMeasured) result.status |= kStatusImuGap;
    bridge_imu_gaps(intervals, gaps, start, last_angular_rate_, start.gravity);
  }
  ImuPreintegration preintegration(start.gyro_bias, start.accel_bias, noise_);
  for (const auto& iv : intervals) preintegration.integrate(iv.gyro, iv.accel, iv.dt);
  NavState predicted = preintegration.predict(start, start.gravity);
  predicted.time = t_end;
  StateCovariance covariance = propagate_covariance(preintegration, start);
  if (!gaps.empty()) widen_for_imu_gaps(covariance, gaps);
  PoseTable relative = deskew_trajectory(config_.odometry.deskew, scan.start_time + extrinsics_.lidar_time_offset_s, t_end,
                                         start, predicted, intervals, last_angular_rate_);
  return {start, std::move(intervals), std::move(preintegration), predicted, covariance, std::move(relative)};
}

// Forster et al.'s preintegration noise, mapped into the error state, and the biases' random walk.
StateCovariance LidarInertialOdometry::propagate_covariance(const ImuPreintegration& pre, const NavState& start) const {
  const StateCovariance f = imu_transition(pre, start);
  const double dt = pre.duration();
  const Eigen::Matrix3d& r = start.rotation;
  // Preintegration noise [dphi, dv, dp] into the state order [theta, p, v].
  Eigen::Matrix<double, kStateDim, 9> g = Eigen::Matrix<double, kStateDim, 9>::Zero();
  g.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity();
  g.block<3, 3>(6, 3) = r;
  g.block<3, 3>(3, 6) = r;
  StateCovariance q = g * pre.covariance() * g.transpose();
  q.block<3, 3>(9, 9) += Eigen::Matrix3d::Identity() * noise_.gyro_bias_random_walk * noise_.gyro_bias_random_walk * dt;
  q.block<3, 3>(12, 12) += Eigen::Matrix3d::Identity() * noise_.accel_bias_random_walk * noise_.accel_bias_random_walk * dt;
  StateCovariance out = f * covariance_ * f.transpose() + q;
  return 0.5 * (out + out.transpose());
}

DeskewedFeatures LidarInertialOdometry::deskew(const Scan& scan, const ScanFeatures& indices,
                                               const PoseTable& relative) const {
  return deskew_features(scan, indices, relative, scan.start_time + extrinsics_.lidar_time_offset_s, lidar_to_imu_,
                         beam_calibration_, deskew_params_, window_.keyframes().size() >= kFlattestQueriesFromKeyframe);
}

UpdateResult LidarInertialOdometry::update(const Prediction& prediction, const DeskewedFeatures& features,
                                           const UpdateParams& params) const {
  return iterated_update(prediction.predicted, prediction.covariance, features.planes, window_.plane_map(),
                         features.edges, window_.edge_map(), params, &window_.post_axis_map());
}

void LidarInertialOdometry::register_scan(const Scan& scan, const ScanFeatures& indices, Prediction& prediction,
                                          DeskewedFeatures& features, OdometryResult& result) {
  const double duration = prediction.preintegration.duration();
  result.forward_hold = holds_.forward_held();
  holds_.apply(prediction.covariance, prediction.predicted);
  UpdateParams params = update_params_;
  if (move_off_.active()) {
    const bool rocking = start_up_.body_motion_until(imu_, prediction.predicted.time) == BodyMotion::kRocking;
    move_off_.restrict(params, prediction.covariance, rocking);
  }
  UpdateResult updated = update(prediction, features, params);
  if (velocity_std(prediction.covariance) > kTrustedVelocityStd && config_.odometry.deskew == DeskewMode::kImu) {
    // Rolling start: the deskew assumed the prior speed. Deskew again with the speed the LiDAR
    // just measured (the start velocity the updated end state implies) and update again.
    const NavState& start = prediction.start;
    NavState corrected_start = start;
    corrected_start.velocity = updated.state.velocity - updated.state.gravity * duration -
                               start.rotation * prediction.preintegration.delta_velocity(start.gyro_bias, start.accel_bias);
    prediction.relative = deskew_trajectory(
        DeskewMode::kImu, scan.start_time + extrinsics_.lidar_time_offset_s, prediction.predicted.time, corrected_start,
        prediction.preintegration.predict(corrected_start, corrected_start.gravity), prediction.intervals,
        last_angular_rate_);
    features = deskew(scan, indices, prediction.relative);
    updated = update(prediction, features, params);
  }
  const bool turning = turning_faster_than(prediction.start, prediction.predicted, updated.state, duration,
                                           config_.odometry.hold_release_yaw_rate_deg_s);
  const double weakest_translation = updated.min_translation_eigenvalue;
  if (holds_.imu_contradicts(updated.state, prediction.predicted, prediction.covariance)) {
    hold_imu_states(prediction.covariance);
    updated = update(prediction, features, params);
    result.status |= kStatusImuInconsistent;
    bridge_contradicting_imu(scan, indices, params, prediction, features, updated);
  }
  holds_.decide_next(weakest_translation, turning);
  state_ = updated.state;
  state_.time = prediction.predicted.time;
  covariance_ = updated.covariance;
  result.velocity_correction_body = state_.rotation.transpose() * (state_.velocity - prediction.predicted.velocity);
  const Eigen::Vector3d forward = config_.odometry.forward_axis.normalized();
  holds_.trim(result.forward_hold, forward.dot(result.velocity_correction_body), duration, state_);
  result.residuals = updated.residuals;
  result.iterations = updated.iterations;
  result.rms_residual_m = updated.rms_residual_m;
  result.min_translation_eigenvalue = updated.min_translation_eigenvalue;
  if (updated.degenerate_directions > 0) result.status |= kStatusDegenerate;
  if (updated.residuals < 50) result.status |= kStatusFewFeatures;
}

// Either the IMU's measurements over the scan are wrong (a burst of corrupted or clipped samples)
// or the state it started from is (a rolling start's speed). Predicted and deskewed as over an IMU
// gap instead (the last estimated twist held, the prior widened), a scan whose measurements were
// wrong agrees with the LiDAR, and its points, no longer deskewed with them, fit the map better;
// then that prediction is taken.
void LidarInertialOdometry::bridge_contradicting_imu(const Scan& scan, const ScanFeatures& indices, UpdateParams params,
                                                     Prediction& prediction, DeskewedFeatures& features,
                                                     UpdateResult& updated) {
  OdometryResult unused;
  Prediction bridged = predict(scan, unused, ImuUse::kBridgeWholeScan);
  holds_.apply(bridged.covariance, bridged.predicted);
  if (move_off_.active()) move_off_.restrict(params, bridged.covariance, false);
  hold_imu_states(bridged.covariance);
  DeskewedFeatures bridged_features = deskew(scan, indices, bridged.relative);
  UpdateResult bridged_update = update(bridged, bridged_features, params);
  if (!holds_.consistent(bridged_update.state, bridged.predicted, bridged.covariance) ||
      !(bridged_update.rms_residual_m < updated.rms_residual_m)) {
    return;
  }
  prediction = std::move(bridged);
  features = std::move(bridged_features);
  updated = bridged_update;
}

void LidarInertialOdometry::update_map(const DeskewedFeatures& features, OdometryResult& result) {
  // The first keyframes of a rolling start were deskewed with an unknown speed: once the speed
  // is known, the map starts afresh from the current, correctly deskewed scan.
  if (!map_trusted_ && velocity_std(covariance_) < kTrustedVelocityStd) {
    map_trusted_ = true;
    window_.restart();
  }
  if (config_.odometry.beam_calibration && map_trusted_ && !window_.plane_map().empty()) {
    update_beam_calibration(beam_calibration_, features, state_, lidar_to_imu_, window_.plane_map(),
                            update_params_.correspondence, config_.odometry.lidar_noise_m);
  }
  // A scan too poor to register on the map (blinded or garbage returns) has nothing to add to it
  // either; as a keyframe it would only push good keyframes out of the window.
  if (!(result.status & kStatusFewFeatures) && window_.consider(features, state_, result.hausdorff_m)) {
    result.status |= kStatusKeyframe;
    window_.set_newest_for_backend(covariance_.topLeftCorner<6, 6>(),
                                   imu_since_keyframe_measured_ ? std::move(imu_since_keyframe_) : std::vector<ImuInterval>{});
    imu_since_keyframe_.clear();
    imu_since_keyframe_measured_ = true;
  }
  move_off_.update(state_.position, window_.keyframes().size());
}

// What the prediction integrated, appended to the stretch since the last keyframe. Bridged
// intervals (an IMU gap, an IMU the LiDAR contradicted) are the last twist held, not measurements:
// such a stretch gives the backend no IMU factor.
void LidarInertialOdometry::keep_keyframe_imu(const Prediction& prediction, std::uint32_t status) {
  if (status & (kStatusImuGap | kStatusImuInconsistent)) imu_since_keyframe_measured_ = false;
  if (!imu_since_keyframe_measured_) return;
  imu_since_keyframe_.insert(imu_since_keyframe_.end(), prediction.intervals.begin(), prediction.intervals.end());
  if (!imu_since_keyframe_.empty() && prediction.predicted.time - imu_since_keyframe_.front().start_time > kKeyframeImuSpan_s) {
    imu_since_keyframe_.clear();
    imu_since_keyframe_measured_ = false;
  }
}

void LidarInertialOdometry::restart_map_if_lost(Prediction& prediction) {
  if (window_.plane_map().empty()) return;
  const StateCovariance transition = imu_transition(prediction.preintegration, prediction.start);
  if (!reinit_.beyond_basin(relative_prediction_covariance(prediction.covariance, transition, covariance_))) return;
  // The map left behind is out of the prediction's reach: a new one from the dead-reckoned state,
  // deskewed and registered from here on as after a rolling start until the velocity is known.
  window_.restart();
  map_trusted_ = false;
  reinit_.begin_new_map(prediction.covariance);
}

void LidarInertialOdometry::check_recovery(OdometryResult& result) {
  if (!reinit_.check(result.state, result.covariance)) {
    // Nothing of this state can be trusted, its biases and velocity least: the start-up again,
    // with the IMU samples still held, and the pose placed where the last plausible one was.
    initialized_ = false;
    start_up_.abandon();
    window_.restart();
    imu_since_keyframe_.clear();
    imu_since_keyframe_measured_ = false;
    map_trusted_ = false;
    holds_ = BiasHolds(bias_hold_config(config_.odometry));
    move_off_ = MoveOff(move_off_config(config_.odometry));
    result.status |= kStatusInitializing;
    return;
  }
  if (reinit_.recovering()) {
    const bool registered = result.residuals > 0;  // on a map, not the prediction taken for the first keyframe
    const bool constrained = (result.status & (kStatusDegenerate | kStatusFewFeatures)) == 0;
    if (!reinit_.converged(map_trusted_, registered, constrained)) result.status |= kStatusInitializing;
  }
  // The new maps' frames lie where the dead reckoning put them: the published pose is that
  // uncertain in the first map's frame.
  if (reinit_.new_maps() > 0) result.covariance.block<3, 3>(3, 3) += reinit_.frame_position_covariance();
}

}  // namespace liod
