#include "liod/sweep_registration.hpp"

#include <cmath>
#include <numbers>

#include "liod/beam_calibration.hpp"
#include "liod/gravity_alignment.hpp"
#include "liod/local_map.hpp"
#include "liod/unit_configs.hpp"

namespace liod {

SweepRegistrationConfig sweep_registration_config(const FrontEndConfig& config) {
  SweepRegistrationConfig c;
  c.features = feature_params(config);
  c.update = update_params(config);
  // The speed comes from the rounds, not from the update's prior: the update's own vertical
  // velocity constraint would act on a velocity it has no covariance for.
  c.update.vertical_velocity_std = 0.0;
  c.lidar_to_imu = {config.extrinsics.lidar_to_imu_rotation, config.extrinsics.lidar_to_imu_translation};
  c.lidar_time_offset_s = config.extrinsics.lidar_time_offset_s;
  c.noise.gyro_noise_density = config.imu.gyro_noise_density;
  c.noise.accel_noise_density = config.imu.accel_noise_density;
  c.noise.gyro_bias_random_walk = config.imu.gyro_bias_random_walk;
  c.noise.accel_bias_random_walk = config.imu.accel_bias_random_walk;
  c.map_voxel_m = config.odometry.map_voxel_m;
  c.map_points_per_voxel = config.odometry.map_points_per_voxel;
  c.map_min_point_spacing_m = config.odometry.map_min_point_spacing_m;
  c.deskew.map_min_point_spacing_m = config.odometry.map_min_point_spacing_m;
  return c;
}

struct SweepRegistration::Round {
  NavState first_end;  // the first sweep's end state, as the IMU carried the start to it
  UpdateResult second_end;
};

SweepRegistration::SweepRegistration(SweepRegistrationConfig config) : config_(std::move(config)) {}

void SweepRegistration::add_imu(const ImuSample& sample) {
  if (!imu_.empty() && sample.time < imu_.back().time) return;
  imu_.push_back(sample);
}

namespace {

NavState integrate(const NavState& start, const std::vector<ImuInterval>& intervals, const ImuNoise& noise, double end) {
  ImuPreintegration pre(start.gyro_bias, start.accel_bias, noise);
  for (const auto& iv : intervals) pre.integrate(iv.gyro, iv.accel, iv.dt);
  NavState out = pre.predict(start, start.gravity);
  out.time = end;
  return out;
}

std::vector<Eigen::Vector3d> to_world(const std::vector<Eigen::Vector3d>& body, const NavState& state) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(body.size());
  for (const auto& p : body) out.push_back(state.to_world(p));
  return out;
}

}  // namespace

// One round: both sweeps deskewed with the IMU from `start` (the first sweep's start, at the
// speed of this round), the first mapped at its IMU-predicted end, the second registered on it.
SweepRegistration::Round SweepRegistration::run_round(const Scan& first, const ScanFeatures& first_features,
                                                      const Scan& second, const ScanFeatures& second_features,
                                                      const NavState& start) const {
  const double offset = config_.lidar_time_offset_s;
  const double first_end = first.end_time + offset;
  const double second_end = second.end_time + offset;
  const BeamCalibration no_calibration;
  const auto first_intervals = imu_intervals(imu_, start.time, first_end);
  Round round;
  round.first_end = integrate(start, first_intervals, config_.noise, first_end);
  const PoseTable first_relative = deskew_trajectory(DeskewMode::kImu, start.time, first_end, start, round.first_end,
                                                     first_intervals, Eigen::Vector3d::Zero());
  const DeskewedFeatures mapped = deskew_features(first, first_features, first_relative, start.time,
                                                  config_.lidar_to_imu, no_calibration, config_.deskew, false);
  LocalMap planes(config_.map_voxel_m, config_.map_points_per_voxel, config_.map_min_point_spacing_m);
  LocalMap edges(config_.map_voxel_m, config_.map_points_per_voxel, config_.map_min_point_spacing_m);
  planes.add(to_world(mapped.map_planes, round.first_end), 0);
  edges.add(to_world(mapped.edges, round.first_end), 0);

  const auto second_intervals = imu_intervals(imu_, first_end, second_end);
  const NavState predicted = integrate(round.first_end, second_intervals, config_.noise, second_end);
  const PoseTable second_relative = deskew_trajectory(DeskewMode::kImu, second.start_time + offset, second_end,
                                                      round.first_end, predicted, second_intervals, Eigen::Vector3d::Zero());
  const DeskewedFeatures queries = deskew_features(second, second_features, second_relative, second.start_time + offset,
                                                   config_.lidar_to_imu, no_calibration, config_.deskew, false);
  StateCovariance prior = StateCovariance::Identity() * 1e-8;  // biases and gravity: held
  const double rotation_std = config_.rotation_std_deg * std::numbers::pi / 180.0;
  prior.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity() * rotation_std * rotation_std;
  prior.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * config_.position_std_m * config_.position_std_m;
  prior.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity();  // untouched by a pose-only update
  round.second_end = iterated_update(predicted, prior, queries.planes, planes, queries.edges, edges, config_.update);
  return round;
}

std::optional<SweepMotion> SweepRegistration::register_pair(const Scan& first, const Scan& second) const {
  const double offset = config_.lidar_time_offset_s;
  const double t0 = first.start_time + offset;
  const double t1 = first.end_time + offset;
  const double t2 = second.end_time + offset;
  if (imu_.empty() || !(t0 < t1 && t1 < t2)) return std::nullopt;
  // Gravity's direction from the mean specific force over the pair: a vehicle's own acceleration
  // tilts it, which over 0.2 s moves the prediction by millimetres.
  const auto alignment = align_gravity(imu_, t0, t2, config_.min_alignment_samples);
  if (!alignment) return std::nullopt;
  FeatureExtractor extractor(config_.features);
  ScanFeatures first_features;
  ScanFeatures second_features;
  extractor.extract(first, first_features);
  extractor.extract(second, second_features);

  NavState start;
  start.time = t0;
  start.rotation = alignment->rotation;
  // Start from a standstill: each round moves the start velocity by the difference between the
  // first sweep's end velocity the registration implies and the one the round assumed.
  SweepMotion motion;
  Round round;
  Eigen::Vector3d velocity_change = Eigen::Vector3d::Zero();
  for (int r = 0; r < config_.rounds; ++r) {
    round = run_round(first, first_features, second, second_features, start);
    motion.rounds = r + 1;
    if (round.second_end.residuals == 0) return std::nullopt;
    const double dt = t2 - t1;
    const Eigen::Vector3d predicted_shift = integrate(round.first_end, imu_intervals(imu_, t1, t2), config_.noise, t2).position -
                                            round.first_end.position;
    const Eigen::Vector3d measured_shift = round.second_end.state.position - round.first_end.position;
    velocity_change = (measured_shift - predicted_shift) / dt;
    start.velocity += velocity_change;
    if (velocity_change.norm() < config_.speed_tolerance_m_s) break;
  }
  const NavState& a = round.first_end;
  const NavState& b = round.second_end.state;
  motion.body = Pose{Eigen::Quaterniond(a.rotation), a.position}.inverse() * Pose{Eigen::Quaterniond(b.rotation), b.position};
  motion.lidar = config_.lidar_to_imu.inverse() * motion.body * config_.lidar_to_imu;
  motion.velocity_body = a.rotation.transpose() * (a.velocity + velocity_change);
  motion.residuals = round.second_end.residuals;
  motion.rms_residual_m = round.second_end.rms_residual_m;
  motion.degenerate_directions = round.second_end.degenerate_directions;
  return motion;
}

}  // namespace liod
