#include "liod/lidar_inertial_odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "liod/angles.hpp"
#include "liod/gravity_alignment.hpp"
#include "liod/hausdorff.hpp"
#include "liod/map_correspondence.hpp"
#include "liod/so3.hpp"
#include "liod/speed_search.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

// While the speed is this uncertain, the deskew of the first scans is unreliable (rolling start).
constexpr double kTrustedVelocityStd = 0.3;
// The IMU kept at most, back from its newest sample.
constexpr double kImuHistory_s = 60.0;
// Scans the IMU must have agreed with the LiDAR (odometry.max_prediction_nis) before a turn releases
// the forward hold.
constexpr int kConsistentScansToRelease = 50;
// Rolling start (speed_search.hpp): farther returns add little but the gyro's error, scaled by range.
constexpr double kStructureRange_m = 80.0;
constexpr double kStructureVoxel_m = 0.1;    // thinning of the structure points (3-D)
constexpr double kFootprintRadius_m = 0.12;  // posts are 8 cm; the fine speed step moves 5 mm per 0.1 s
constexpr double kMinSpeedScore = 20.0;      // about as many structure points matched (a pair, or all summed)
// A scan's structure is scored against this many scans before it: a post passes a sensor-locked
// window within a few scans, and the cost per hypothesis grows with the points held (twenty dense
// urban scans took a minute a scan when the search was kept from deciding).
constexpr std::size_t kSpeedSearchMemory = 4;
// And at most this many structure points a scan off the rails: a search call places and indexes
// each hypothesis's union anew, and a dense town start (5,800 a scan) took 0.7-1.7 s a call, which
// a standstill repeats until the IMU has had its say (half a second). Sparse roads hold 15-40.
constexpr std::size_t kMaxSearchPointsPerScan = 2500;
// Without that much structure off the rails for so long, the first scans' standstill stands if
// they saw one, else the speed is left to the LiDAR's registration under the wide prior.
constexpr double kMaxSpeedSearch_s = 2.0;
// The speed with all of the structure is decided on this scan (0 the first), from its overlap and
// that of each scan before it with their predecessors, summed. From the first pair alone (1) it
// aliased: 32 highway starts at 10-17 m/s, 4 s each, had two at ~2 m/s for 15 and 17 m/s (17 m
// and 19 m ATE) and one 11 % low; with the third scan also scored against both before it (2), the
// worst speed was 5 % off and the worst ATE 0.85 m (docs/odometry.md, 2026-12-02). Deciding on the
// fourth (3) let a standstill that rides along with the sensor gather weight on one start (2.7 m).
constexpr std::size_t kAllStructureScans = 2;
// Below this a pair's best speed may be the rails' standstill (off_along_track_lines).
constexpr double kStandstillSpeed = 1.0;
// The rails-free search's best speed must lead every other peak at least kMinAliasSeparation
// from it by kMinLeadOverAliases (stands_clear_of_aliases). Guard-rail posts 4 m apart put an
// alias of 15 m/s at 15 - 4 m / (k 0.1 s) for each scan k back (-25, -5, 1.7, 5 m/s) and one at
// 55: of 100 highway and urban 4 s starts at 10-17 m/s three were decided at -5.1, 50.3 (the
// grid's end, still rising) and near 0 m/s (12-39 m ATE in 4 s), and the 180 s highway seed 19
// at -3.8 (771 m); with a 1.3 lead none, the worst 0.52 m (docs/odometry.md, 2026-12-04, third
// session).
constexpr double kMinAliasSeparation = 2.0;
constexpr double kMinLeadOverAliases = 1.3;
// From this keyframe on each plane query is the flattest candidate of its voxel (deskew_features).
constexpr std::size_t kFlattestQueriesFromKeyframe = 3;
// A standstill's evidence off the rails falls off to either side of zero; at 3 m/s it is on its
// shoulder still. A moving car whose rings cut the rail's faces in spots fixed in the sensor's
// frame scores a standstill too, but its true speed peaks on its own: highway seed 131 at 13 m/s,
// 0.77-0.92 of the standstill's score over its first 2 s; rocked at rest, the highway's separate
// peaks reach 0.2 of the standstill's, the tunnel's 0.2 (docs/odometry.md, 2026-12-02).
constexpr double kMinMovingPeakSpeed = 3.0;
constexpr double kMinMovingPeakShare = 0.5;
// Beam calibration: ground is a plane within 26 deg of level; a residual beyond 10 cm is a wrong
// match, not a millimetre beam offset. Beams below the horizon only, 8 m away or more: nearer, an
// offset moves a point by under a millimetre (range * offset), and what matters is the far ground.
constexpr double kGroundNormalCos = 0.9;
constexpr double kBeamResidualGateM = 0.1;
constexpr double kBeamMinRangeM = 8.0;
constexpr double kBeamMaxElevationRad = -0.01;
// Every 4th of those per beam: the offsets are constant, the sums keep ~1000 scans, and the search
// for each point's plane costs time (urban s1 60 s median per scan: every point 11.7 ms, every
// 4th 8.9 ms, no calibration 8.4 ms).
constexpr std::uint32_t kBeamPointStride = 4;

}  // namespace

FeatureParams LidarInertialOdometry::feature_params(const Config& config) {
  const OdometryConfig& o = config.odometry;
  const ExtrinsicsConfig& extrinsics = config.extrinsics;
  FeatureParams p;
  p.neighbourhood = o.curvature == CurvatureMode::kAdaptive ? CurvatureNeighbourhood::kDistanceAdaptive
                                                             : CurvatureNeighbourhood::kFixed;
  p.min_range_m = o.min_range_m;
  p.max_range_m = o.max_range_m;
  p.occlusion_jump_m = o.occlusion_jump_m;
  p.edge_curvature = o.edge_curvature;
  p.plane_curvature = o.plane_curvature;
  p.sectors_per_ring = o.sectors_per_ring;
  p.max_edges_per_sector = o.max_edges_per_sector;
  p.surface_end_extrapolation = o.surface_end_extrapolation;
  p.post_max_width_m = o.post_edges ? o.post_max_width_m : 0.0;
  p.post_depth_m = o.post_depth_m;
  p.crossing_edge_tolerance_m = o.crossing_edge_tolerance_m;
  if ((o.crop_box_min_m.array() < o.crop_box_max_m.array()).all()) {
    CropBox box;
    box.sensor_to_body.linear() = extrinsics.lidar_to_imu_rotation.toRotationMatrix().cast<float>();
    box.sensor_to_body.translation() = extrinsics.lidar_to_imu_translation.cast<float>();
    box.min = o.crop_box_min_m.cast<float>();
    box.max = o.crop_box_max_m.cast<float>();
    p.self_crop = box;
  }
  return p;
}

namespace {

std::vector<Eigen::Vector3d> transformed(const std::vector<Eigen::Vector3d>& points, const NavState& s) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(s.to_world(p));
  return out;
}

double velocity_std(const StateCovariance& p) { return std::sqrt(p.block<3, 3>(6, 6).diagonal().maxCoeff()); }

struct TimeSpan {
  double from = 0.0;
  double to = 0.0;
};

// Where the IMU is silent within [from, to]: between consecutive samples more than max_gap apart,
// before the first sample when it begins more than max_gap after `from` (the buffer keeps a minute),
// and after the last sample when it ends more than max_gap before `to`.
std::vector<TimeSpan> imu_gaps(const std::deque<ImuSample>& imu, double from, double to, double max_gap) {
  std::vector<TimeSpan> gaps;
  auto add = [&](double a, double b) {
    a = std::max(a, from);
    b = std::min(b, to);
    if (b > a) gaps.push_back({a, b});
  };
  if (imu.front().time - from > max_gap) add(from, imu.front().time);
  for (std::size_t i = 1; i < imu.size(); ++i) {
    if (imu[i].time - imu[i - 1].time > max_gap) add(imu[i - 1].time, imu[i].time);
  }
  if (to - imu.back().time > max_gap) add(imu.back().time, to);
  return gaps;
}

// Nothing was measured over an IMU gap. Holding the last sample there (one sample's vibration,
// and the turn rate from before the gap, for seconds) smears the deskew and biases the
// prediction, so the intervals in a gap carry the last estimated twist instead: constant body
// velocity and angular rate, as an IMU would have measured them. Prediction and deskew use it alike.
void bridge_imu_gaps(std::vector<ImuInterval>& intervals, const std::vector<TimeSpan>& gaps, const NavState& start,
                     const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& gravity) {
  const Eigen::Vector3d v_body = start.rotation.transpose() * start.velocity;
  const Eigen::Vector3d gyro = angular_rate + start.gyro_bias;
  const Eigen::Vector3d accel = angular_rate.cross(v_body) - start.rotation.transpose() * gravity + start.accel_bias;
  for (auto& iv : intervals) {
    const double mid = iv.start_time + 0.5 * iv.dt;
    for (const auto& gap : gaps) {
      if (mid > gap.from && mid < gap.to) {
        iv.gyro = gyro;
        iv.accel = accel;
        break;
      }
    }
  }
}

// Even so the motion over a gap is a guess: the prior is widened by what a road vehicle may do
// meanwhile (angular rate and acceleration changing by this much, 1 sigma), and the LiDAR decides.
constexpr double kGapAngularRateStd = 0.5;   // rad/s
constexpr double kGapAccelerationStd = 1.0;  // m/s^2

void widen_for_imu_gaps(StateCovariance& p, const std::vector<TimeSpan>& gaps) {
  double gap = 0.0;
  for (const auto& g : gaps) gap += g.to - g.from;
  const Eigen::Matrix3d i = Eigen::Matrix3d::Identity();
  const double w = kGapAngularRateStd * gap;
  const double a2 = kGapAccelerationStd * kGapAccelerationStd;
  p.block<3, 3>(0, 0) += i * w * w;
  p.block<3, 3>(3, 3) += i * a2 * std::pow(gap, 4) / 4.0;  // p += a t^2 / 2
  p.block<3, 3>(3, 6) += i * a2 * std::pow(gap, 3) / 2.0;
  p.block<3, 3>(6, 3) += i * a2 * std::pow(gap, 3) / 2.0;
  p.block<3, 3>(6, 6) += i * a2 * gap * gap;               // v += a t
}

// Zeroes the cross-covariance between the error-state subspace spanned by the orthonormal
// columns of u and the rest of the state: pose residuals then cannot move those components, and
// their covariance among themselves stays as it was (as do the state's other covariances).
template <int kColumns>
void decouple_subspace(StateCovariance& p, const Eigen::Matrix<double, kStateDim, kColumns>& u) {
  const StateCovariance inside = u * u.transpose();
  const StateCovariance across = StateCovariance::Identity() - inside;
  p = across * p * across + inside * p * inside;
}

// What the along-track pull of a weak scene would otherwise move: the accelerometer bias along the
// vehicle's forward axis, and the tilt of gravity that reads as an acceleration along the track.
// Held together: at a standstill the filter knows their sum (the specific force) far better than
// either, and holding them apart would forget that.
void hold_forward_acceleration(StateCovariance& p, const NavState& x, const Eigen::Vector3d& forward_body) {
  Eigen::Matrix<double, kStateDim, 2> u = Eigen::Matrix<double, kStateDim, 2>::Zero();
  u.block<3, 1>(12, 0) = forward_body.normalized();
  // Gravity moved by B dg changes the acceleration by (B dg) x g, along the track by
  // dg . B^T (g x forward).
  const Eigen::Vector2d along = gravity_tangent_basis(x.gravity).transpose() * x.gravity.cross(x.rotation * forward_body);
  if (along.norm() < 1e-9) {
    decouple_subspace<1>(p, u.leftCols<1>());
    return;
  }
  u.block<2, 1>(kGravityIndex, 1) = along.normalized();
  decouple_subspace<2>(p, u);
}

// The gyro's bias about the vehicle's up axis keeps its prior: cut from the heading's update.
void hold_yaw_rate_bias(StateCovariance& p, const Eigen::Vector3d& up_body) {
  Eigen::Matrix<double, kStateDim, 1> u = Eigen::Matrix<double, kStateDim, 1>::Zero();
  u.segment<3>(9) = up_body.normalized();
  decouple_subspace<1>(p, u);
}

// The biases and gravity keep their prior: cut from the pose, velocity and each other's updates.
void hold_imu_states(StateCovariance& p) {
  Eigen::Matrix<double, kStateDim, kStateDim - 9> u = Eigen::Matrix<double, kStateDim, kStateDim - 9>::Zero();
  u.bottomRows<kStateDim - 9>().setIdentity();
  decouple_subspace<kStateDim - 9>(p, u);
}

// Whether the IMU prediction and the update both turned the body about the vertical faster than
// this many deg/s over the scan (0: never). The update alone would count the LiDAR's corrections
// at a static start as turns; the IMU alone, one whose clock is off, turning where the vehicle
// does not.
bool turning_faster_than(const NavState& start, const NavState& predicted, const NavState& updated, double duration,
                         double yaw_rate_deg_s) {
  if (yaw_rate_deg_s <= 0.0 || duration <= 0.0) return false;
  const Eigen::Vector3d up = start.gravity.normalized();
  const double threshold = yaw_rate_deg_s * kDegToRad;
  return std::abs(so3::turn_rate_about(start.rotation, predicted.rotation, up, duration)) > threshold &&
         std::abs(so3::turn_rate_about(start.rotation, updated.rotation, up, duration)) > threshold;
}

// How far the update moved the pose from the IMU prediction, in the prediction's own covariance
// (squared Mahalanobis distance over the 6 pose dimensions). On the simulated drives at most
// 26-144 (99.9 % below 40); with the IMU's stamps 1 s off, 50-19 000.
double prediction_nis(const NavState& updated, const NavState& predicted, const StateCovariance& predicted_covariance) {
  const Eigen::Matrix<double, 6, 1> pose = boxminus(updated, predicted).head<6>();
  return pose.dot(predicted_covariance.topLeftCorner<6, 6>().ldlt().solve(pose));
}

}  // namespace

LidarInertialOdometry::LidarInertialOdometry(const Config& config)
    : config_(config),
      extrinsics_(config.extrinsics),
      lidar_to_imu_{config.extrinsics.lidar_to_imu_rotation, config.extrinsics.lidar_to_imu_translation},
      extractor_(feature_params(config)),
      held_bias_trim_(config.odometry.held_bias_trim_window_s, config.odometry.held_bias_trim_gain),
      plane_map_(config.odometry.map_voxel_m, config.odometry.map_points_per_voxel, config.odometry.map_min_point_spacing_m),
      edge_map_(config.odometry.map_voxel_m, config.odometry.map_points_per_voxel, config.odometry.map_min_point_spacing_m),
      post_axis_map_(edge_map_) {
  noise_.gyro_noise_density = config.imu.gyro_noise_density;
  noise_.accel_noise_density = config.imu.accel_noise_density;
  noise_.gyro_bias_random_walk = config.imu.gyro_bias_random_walk;
  noise_.accel_bias_random_walk = config.imu.accel_bias_random_walk;
  update_params_.max_iterations = config.odometry.max_iterations;
  update_params_.forced_searches = config.odometry.forced_searches;
  update_params_.lidar_noise_m = config.odometry.lidar_noise_m;
  update_params_.correspondence.neighbours = config.odometry.correspondence_neighbours;
  update_params_.correspondence.max_distance_m = config.odometry.correspondence_gate_m;
  update_params_.correspondence.max_plane_thickness_m = config.odometry.plane_thickness_m;
  update_params_.correspondence.fit_uncertainty = config.odometry.fit_uncertainty;
  if (config.odometry.edge_residual == EdgeResidual::kAlongRay) {
    update_params_.edge_viewpoint_body = config.extrinsics.lidar_to_imu_translation;
    if (config.odometry.post_edges) {
      update_params_.posts = PostParams{};
      update_params_.posts->depth_m = config.odometry.post_depth_m;
    }
  }
  update_params_.degeneracy_eigenvalue = config.odometry.degeneracy_eigenvalue;
  update_params_.project_degenerate = config.odometry.degeneracy_projection;
  update_params_.vertical_velocity_std = config.odometry.vertical_velocity_std_mps;
  update_params_.vertical_axis = config.odometry.up_axis;
}

void LidarInertialOdometry::add_imu(const ImuSample& sample) {
  const bool finite = std::isfinite(sample.time) && sample.gyro.allFinite() && sample.accel.allFinite();
  if (!finite || (!imu_.empty() && sample.time <= imu_.back().time)) {
    ++dropped_imu_;
    return;
  }
  imu_.push_back(sample);
  // Without scans (a LiDAR dead or not yet connected) nothing else trims the buffer, and a daemon
  // left so for a day would hold a gigabyte of samples. A scan after a longer silence is
  // predicted across the missing start as over any IMU gap.
  while (imu_.size() > 2 && imu_.front().time < sample.time - kImuHistory_s) imu_.pop_front();
}

double LidarInertialOdometry::latest_imu_time() const {
  return imu_.empty() ? -std::numeric_limits<double>::infinity() : imu_.back().time;
}

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

PoseTable LidarInertialOdometry::deskew_trajectory(const Scan& scan, const NavState& start, const NavState& end,
                                                   const std::vector<ImuInterval>& intervals) const {
  PoseTable table;
  const double t_start = scan.start_time + extrinsics_.lidar_time_offset_s;
  const double t_end = scan_end_time(scan);
  switch (config_.odometry.deskew) {
    case DeskewMode::kImu: {
      table = integrate_imu_poses(start, intervals, start.gravity);
      table.make_relative_to({Eigen::Quaterniond(end.rotation), end.position});
      break;
    }
    case DeskewMode::kConstantVelocity: {
      // LOAM's assumption: the last estimated twist holds through the sweep.
      const Eigen::Vector3d v_body = end.rotation.transpose() * end.velocity;
      constexpr int kSteps = 10;
      for (int k = 0; k <= kSteps; ++k) {
        const double t = t_start + (t_end - t_start) * k / kSteps;
        const double before_end = t_end - t;
        table.add(t, {Eigen::Quaterniond(so3::exp(-last_angular_rate_ * before_end)), -v_body * before_end});
      }
      break;
    }
    case DeskewMode::kNone:
      table.add(t_end, {});
      break;
  }
  return table;
}

void LidarInertialOdometry::deskew_features(const Scan& scan, const ScanFeatures& indices, const PoseTable& relative,
                                            Features& out) const {
  const double t0 = scan.start_time + extrinsics_.lidar_time_offset_s;
  const double inverse_map_spacing = 1.0 / std::max(config_.odometry.map_min_point_spacing_m, 0.05);
  // Thin the candidates on their raw coordinates first, so that only the survivors pay for the
  // per-point pose (a voxel shifts by less than the motion blur, which is all that changes).
  VoxelSet occupied(indices.planes.size());
  std::vector<Eigen::Vector3d> planes;
  planes.reserve(indices.planes.size() / 2);
  std::vector<float> plane_curvatures;
  plane_curvatures.reserve(indices.planes.size() / 2);
  out.map_plane_sources.clear();
  auto lidar_point = [&](const LidarPoint& p) {
    return beam_calibration_.correct(Eigen::Vector3d(p.x, p.y, p.z), p.ring);
  };
  auto deskewed = [&](const LidarPoint& p, const Eigen::Vector3d& in_lidar) {
    return relative.at(t0 + static_cast<double>(p.time)) * (lidar_to_imu_ * in_lidar);
  };
  for (std::size_t n = 0; n < indices.planes.size(); ++n) {
    const LidarPoint& p = scan.points[indices.planes[n]];
    if (occupied.insert(voxel_of(Eigen::Vector3d(p.x, p.y, p.z), inverse_map_spacing))) {
      const Eigen::Vector3d in_lidar = lidar_point(p);
      planes.push_back(deskewed(p, in_lidar));
      plane_curvatures.push_back(indices.plane_curvatures[n]);
      out.map_plane_sources.push_back({p.ring, in_lidar});
    }
  }
  std::vector<Eigen::Vector3d> edges;
  edges.reserve(indices.edges.size());
  for (std::size_t e = 0; e < indices.edges.size(); ++e) {
    const LidarPoint& p = scan.points[indices.edges[e]];
    edges.push_back(deskewed(p, lidar_point(p) + indices.edge_shifts[e].cast<double>()));
  }
  // The map keeps planes denser than the queries so that each query finds a tight neighbourhood.
  out.map_planes = planes;
  // Each query is the flattest candidate of its voxel rather than the first (the extractor lists
  // them sharpest first, and a ring crossing an edge or bent by its range noise scores highest):
  // highway 180 s, ten rolling drives, 13.2 -> 11.2 m ATE summed, nine less short along the
  // track. Not against the first two keyframes' map: there it broke two rolling starts (the third
  // scan's speed pulled 1.1 m/s) and the tunnel's static start (docs/odometry.md, 2026-12-03).
  if (keyframes_.size() >= kFlattestQueriesFromKeyframe) {
    out.planes = voxel_downsample_lowest(planes, plane_curvatures, config_.odometry.plane_voxel_m);
  } else {
    out.planes = voxel_downsample(planes, config_.odometry.plane_voxel_m);
  }
  out.edges = voxel_downsample(edges, config_.odometry.edge_voxel_m);
}

// Each plane point of the scan against the map at the updated pose: its residual and how it
// would move with its beam's elevation or range. Elevations from the far ground only: there an
// elevation offset moves a point across the surface (along the ray on a wall it hardly does) and
// the map is densest. Ranges, when learned, from every other plane point.
void LidarInertialOdometry::learn_beam_calibration(const Features& features) {
  const Eigen::Matrix3d world_from_lidar = state_.rotation * lidar_to_imu_.rotation.toRotationMatrix();
  const Eigen::Vector3d up = -state_.gravity.normalized();
  const double noise = config_.odometry.lidar_noise_m;
  const double max_elevation_slope = std::tan(kBeamMaxElevationRad);
  const bool learn_ranges = beam_calibration_.learns_ranges();
  // The candidates (the far ground below the horizon, or every plane point when ranges are learned),
  // every kBeamPointStride-th of each beam.
  struct Picked {
    std::size_t index;
    double horizontal;  // its range across the LiDAR's axis
    bool far_below_horizon;
  };
  std::vector<Picked> picked;
  std::vector<Eigen::Vector3d> world;
  std::vector<std::uint32_t> seen(beam_calibration_.beams(), 0);
  for (std::size_t i = 0; i < features.map_planes.size(); ++i) {
    const RingPoint& source = features.map_plane_sources[i];
    const double horizontal = std::hypot(source.lidar.x(), source.lidar.y());
    const bool far_below_horizon =
        horizontal >= kBeamMinRangeM && source.lidar.z() <= horizontal * max_elevation_slope;
    if (!far_below_horizon && !learn_ranges) continue;
    if (source.ring >= seen.size() || seen[source.ring]++ % kBeamPointStride != 0) continue;  // add_* would drop it
    picked.push_back({i, horizontal, far_below_horizon});
    world.push_back(state_.to_world(features.map_planes[i]));
  }
  // Their planes searched voxel by voxel (as the registration's), added in sweep order.
  std::vector<std::optional<LinearResidual>> planes(picked.size());
  LocalMap::NeighbourSearch search(plane_map_);
  for (const std::uint32_t k : plane_map_.voxel_order(world)) {
    planes[k] = plane_correspondence(search, world[k], update_params_.correspondence);
  }
  for (std::size_t k = 0; k < picked.size(); ++k) {
    const auto& plane = planes[k];
    if (!plane) continue;
    const double residual = plane->evaluate(world[k]);
    if (std::abs(residual) > kBeamResidualGateM) continue;
    const RingPoint& source = features.map_plane_sources[picked[k].index];
    const double variance = noise * noise * plane->variance_scale;
    if (picked[k].far_below_horizon && std::abs(plane->normal.dot(up)) >= kGroundNormalCos) {
      const double elevation = std::atan2(source.lidar.z(), picked[k].horizontal);
      const double jacobian =
          plane->normal.dot(world_from_lidar * BeamCalibration::elevation_derivative(source.lidar));
      beam_calibration_.add_elevation(source.ring, elevation, jacobian, residual, variance);
    } else {
      beam_calibration_.add_range(source.ring, plane->normal.dot(world_from_lidar * source.lidar.normalized()), residual,
                                  variance);
    }
  }
  beam_calibration_.finish_scan();
}

void LidarInertialOdometry::initialize(const Scan& scan, OdometryResult& result) {
  const double t_start = scan.start_time + extrinsics_.lidar_time_offset_s;
  const auto alignment = align_gravity(imu_, t_start - 1.0, scan_end_time(scan));
  if (!alignment) return;
  const auto& o = config_.odometry;
  state_ = NavState{};
  state_.time = t_start;
  state_.rotation = alignment->rotation;
  state_.gyro_bias = alignment->gyro_bias;
  state_.gravity = Eigen::Vector3d(0.0, 0.0, -config_.imu.gravity_m_s2);
  covariance_.setZero();
  const double tilt = o.init_tilt_std_deg * kDegToRad;
  covariance_.diagonal().segment<3>(0) << tilt * tilt, tilt * tilt, 1e-6;  // yaw defines the world frame
  covariance_.diagonal().segment<3>(3).setConstant(1e-6);                    // so does the origin
  covariance_.diagonal().segment<3>(6).setConstant(o.init_velocity_std * o.init_velocity_std);
  // The speed, unknown even at rest, is searched for from the next scan on.
  speed_search_ = SpeedSearch{};
  speed_search_->first_end_time = scan_end_time(scan);
  speed_search_->held.push_back(scan);
  speed_search_->structure.push_back(vertical_structure_points(scan));
  covariance_.diagonal().segment<3>(9).setConstant(o.init_gyro_bias_std * o.init_gyro_bias_std);
  covariance_.diagonal().segment<3>(12).setConstant(o.init_accel_bias_std * o.init_accel_bias_std);
  // The alignment's tilt error is the accelerometer bias over g: as likely as the bias itself.
  const double gravity_tilt = o.init_accel_bias_std / config_.imu.gravity_m_s2;
  covariance_.diagonal().segment<2>(kGravityIndex).setConstant(gravity_tilt * gravity_tilt);
  if (config_.odometry.beam_calibration && beam_calibration_.beams() != scan.beam_count) {
    BeamCalibrationParams params;
    params.learn_ranges = config_.odometry.beam_range_calibration;
    beam_calibration_ = BeamCalibration(scan.beam_count, params);
  }
  initialized_ = true;
  result.status |= kStatusInitializing;
}

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan) { return process(scan, nullptr); }

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan, const ScanFeatures& extracted) {
  return process(scan, &extracted);
}

std::optional<OdometryResult> LidarInertialOdometry::process(const Scan& scan, const ScanFeatures* extracted) {
  OdometryResult result;
  result.points = scan.points.size();
  if (scan.points.empty() || imu_.empty()) return std::nullopt;
  if (!initialized_) {
    initialize(scan, result);
    if (!initialized_) return std::nullopt;
    // Report the attitude only; the pose follows once the speed is known.
    result.state = state_;
    result.covariance = covariance_;
    result.status |= kStatusSpeedUnknown;
    return result;
  }
  if (speed_search_) {
    const double end = scan_end_time(scan);
    if (!(end > scan_end_time(speed_search_->held.back()))) {
      // The LiDAR's clock stepped back. Only the attitude has been reported: start afresh from
      // this scan rather than wait (perhaps for hours) for the old time to come round again.
      speed_search_.reset();
      initialized_ = false;
      return process(scan, extracted);
    }
    // Over an IMU gap the hypotheses' placements would rest on a held sample: decide without it.
    const bool imu_gap = !imu_gaps(imu_, state_.time, end, config_.imu.max_gap_s).empty();
    const bool timed_out = end - speed_search_->first_end_time >= kMaxSpeedSearch_s;
    const BodyMotion motion = body_motion_until(end);
    if (motion == BodyMotion::kRocking) speed_search_->rocked = true;
    std::optional<double> speed;
    if (!imu_gap && !timed_out) speed = search_speed(scan, motion);
    if (speed || imu_gap || timed_out) {
      // Known at last, or not to be known: then first scans that saw a standstill in all of their
      // structure are taken at their word (a car waiting beside a rail) unless the body rocks on its
      // springs (body_rocking.hpp), else the wide prior stays and
      // the LiDAR decides. The state is carried by the IMU to the scan before this one, which
      // becomes the first keyframe. Not through all of the scans so far: with the speed this
      // uncertain, their map pulls the speed towards a standstill scan by scan (highway seed 1,
      // six scans: 14.5 -> 13.3 m/s). But a standstill, whose map pulls the right way, is
      // registered from the first scan on: it may have waited up to kMaxSpeedSearch_s for the
      // body to stop rocking, and the IMU alone, its gyro bias taken from a rocking body, would
      // have tilted the first keyframe (highway 60 s static start rocked for 2.5 s: 6.4 m ATE;
      // from the first scan 0.47 m). A rocking body overrules the first scans' standstill, which
      // may be the rails' (a moving car's first scans between rails see one too), not the
      // standstill off the rails.
      // Still rocking at the end, with the speed that peaks on its own beside the standstill:
      // the body rocks because the car rolls (kMinMovingPeakShare).
      if (!speed && speed_search_->evidence_standstill) speed = speed_search_->moving_peak;
      // A moving speed still short of a clear lead over its aliases is better than none: the LiDAR
      // alone under the wide prior did not find 15 m/s on the highway (seed 18: 767 m ATE).
      if (!speed) speed = speed_search_->unclear_speed;
      if (!speed && (speed_search_->evidence_standstill ||
                     (speed_search_->all_structure_standstill && motion != BodyMotion::kRocking))) {
        speed = 0.0;
      }
      if (speed) start_at_speed(*speed);
      const bool rocked = speed_search_->rocked;
      std::vector<Scan> held = std::move(speed_search_->held);
      speed_search_.reset();
      const bool standstill = speed && std::abs(*speed) < kStandstillSpeed;
      moving_off_ = standstill && config_.odometry.move_off_planes_across;
      standstill_position_ = state_.position;
      if (standstill && rocked) settle_gyro_bias_at_rest(held.front().start_time + extrinsics_.lidar_time_offset_s, end);
      if (standstill) trust_gyro_bias_measured_at_rest();
      for (std::size_t i = standstill ? 0 : held.size() - 1; i < held.size(); ++i) {
        OdometryResult unreported;  // the first keyframe, and the standstill's scans before this one
        process_scan(held[i], nullptr, unreported);
      }
      result.status |= kStatusInitializing;
      process_scan(scan, extracted, result);
      return result;
    }
    speed_search_->held.push_back(scan);
    return std::nullopt;  // no pose until the speed is known
  }
  if (!(scan_end_time(scan) > state_.time)) return std::nullopt;  // a scan from the past (clock jump)
  process_scan(scan, extracted, result);
  return result;
}

LidarInertialOdometry::StructurePoints LidarInertialOdometry::vertical_structure_points(const Scan& scan) const {
  const auto& o = config_.odometry;
  const auto crop = feature_params(config_).self_crop;
  const double t0 = scan.start_time + extrinsics_.lidar_time_offset_s;
  std::vector<TimedPoint> candidates;
  std::vector<Eigen::Vector3d> levelled;  // the motion blur does not change what is vertical
  candidates.reserve(scan.points.size());
  levelled.reserve(scan.points.size());
  for (const auto& p : scan.points) {
    const Eigen::Vector3f sensor(p.x, p.y, p.z);
    const double range = sensor.norm();
    if (!(range >= o.min_range_m && range <= kStructureRange_m) || !std::isfinite(p.time)) continue;  // NaN too
    if (crop && crop->contains(sensor)) continue;  // the car's own body moves with it: a standstill
    const Eigen::Vector3d body = lidar_to_imu_ * sensor.cast<double>();
    candidates.push_back({t0 + static_cast<double>(p.time), body});
    levelled.push_back(state_.rotation * body);
  }
  const std::vector<std::size_t> structure = vertical_structure(levelled, VerticalStructureParams{});
  std::vector<std::size_t> thinned;
  std::vector<Eigen::Vector3d> thinned_levelled;
  VoxelSet occupied(structure.size());
  for (const auto i : structure) {
    if (occupied.insert(voxel_of(levelled[i], 1.0 / kStructureVoxel_m))) {
      thinned.push_back(i);
      thinned_levelled.push_back(levelled[i]);
    }
  }
  // Every stride-th in sweep order, evenly round the scan, within the budget.
  auto within_budget = [&](const std::vector<std::size_t>& indices, std::vector<TimedPoint>& out) {
    const std::size_t stride = std::max<std::size_t>((indices.size() + kMaxSearchPointsPerScan - 1) / kMaxSearchPointsPerScan, 1);
    for (std::size_t k = 0; k < indices.size(); k += stride) out.push_back(candidates[thinned[indices[k]]]);
  };
  StructurePoints out;
  std::vector<std::size_t> every(thinned.size());
  for (std::size_t k = 0; k < every.size(); ++k) every[k] = k;
  within_budget(every, out.all);
  const Eigen::Vector3d forward = state_.rotation * o.forward_axis;
  within_budget(off_along_track_lines(thinned_levelled, forward.head<2>(), AlongTrackLineParams{}), out.off_lines);
  return out;
}

std::optional<double> LidarInertialOdometry::search_speed(const Scan& scan, BodyMotion motion) {
  // A vehicle that may already be moving: the speed is what makes each scan land on the one
  // before. Each hypothesis (a speed along odometry.forward_axis at the first scan: a car does
  // not slide sideways) deskews the scans with the IMU and places them in one frame; their
  // vertical structure is compared from above (speed_search.hpp explains why not the ground, and
  // why not a local registration).
  SpeedSearch& search = *speed_search_;
  const NavState base = state_;
  const auto intervals = imu_intervals(imu_, base.time, scan_end_time(scan));
  if (intervals.empty()) return std::nullopt;
  search.structure.push_back(vertical_structure_points(scan));
  auto placed = [](const std::vector<TimedPoint>& points, const PoseTable& world) {
    std::vector<Eigen::Vector3d> out;
    out.reserve(points.size());
    for (const auto& p : points) out.push_back(world.at(p.time) * p.body);
    return out;
  };
  auto start_at = [&](double speed) {
    NavState start = base;
    start.velocity = base.rotation * (speed * config_.odometry.forward_axis);
    return start;
  };
  auto placement = [&](double speed) { return integrate_imu_poses(start_at(speed), intervals, base.gravity); };
  // The overlap of scan k with the kSpeedSearchMemory scans before it, each placed by one
  // hypothesis's poses. Not with scan k - 1 alone: where a ring passes below a guard rail only in
  // a window fixed in the sensor's frame, consecutive scans see different posts, and a speed that
  // moves each post onto the next one's place in the scan before (about v + spacing / 0.1 s)
  // overlaps as well as the true one (highway seed 2 at 12 m/s: 49 m/s won). Only the true speed
  // also lands a post on itself seen two or more scans before; the alias is off there by a
  // fraction of a spacing.
  auto score_against_earlier = [&](const PoseTable& world, std::size_t k,
                                   std::vector<TimedPoint> StructurePoints::*points) {
    std::vector<Eigen::Vector3d> earlier;
    for (std::size_t j = k > kSpeedSearchMemory ? k - kSpeedSearchMemory : 0; j < k; ++j) {
      const auto placed_j = placed(search.structure[j].*points, world);
      earlier.insert(earlier.end(), placed_j.begin(), placed_j.end());
    }
    return FootprintOverlap(earlier, kFootprintRadius_m).score(placed(search.structure[k].*points, world));
  };
  // Every scan's overlap with those before it, all placed by one hypothesis's poses.
  auto score_since_first = [&](const PoseTable& world, std::vector<TimedPoint> StructurePoints::*points) {
    double sum = 0.0;
    for (std::size_t k = 1; k < search.structure.size(); ++k) sum += score_against_earlier(world, k, points);
    return sum;
  };
  GridSearchParams speeds;
  speeds.min = -10.0;  // reversing
  speeds.max = 50.0;
  speeds.coarse_step = 0.5;
  speeds.fine_step = 0.05;
  const std::size_t newest = search.structure.size() - 1;
  const std::vector<double> hypotheses = coarse_grid(speeds);
  if (newest <= kAllStructureScans) {
    // All the structure: the rails along a road, their posts and ends, tell the speed of a moving
    // vehicle best (the highway's drives: 1-3 % against up to 10 % without the rails).
    search.evidence_all.resize(hypotheses.size(), 0.0);
    for (std::size_t i = 0; i < hypotheses.size(); ++i) {
      search.evidence_all[i] += score_against_earlier(placement(hypotheses[i]), newest, &StructurePoints::all);
    }
    if (newest == kAllStructureScans) {
      const auto best = std::max_element(search.evidence_all.begin(), search.evidence_all.end());
      const GridSearchResult found = refine_around(
          [&](double speed) { return score_since_first(placement(speed), &StructurePoints::all); },
          hypotheses[static_cast<std::size_t>(best - search.evidence_all.begin())], speeds);
      if (found.score >= kMinSpeedScore) {
        if (std::abs(found.value) >= kStandstillSpeed) return found.value;
        search.all_structure_standstill = true;
      }
    }
  }
  // A standstill, or not enough to tell: the rails' footprints move with the sensor and vote for
  // a standstill that may not be (off_along_track_lines), so without them, and summed over the
  // scans until enough structure has passed (one scan on a highway often holds a post or two).
  search.evidence.resize(hypotheses.size(), 0.0);
  for (std::size_t i = 0; i < hypotheses.size(); ++i) {
    search.evidence[i] += score_against_earlier(placement(hypotheses[i]), newest, &StructurePoints::off_lines);
  }
  if (newest < kAllStructureScans) return std::nullopt;
  const auto best = std::max_element(search.evidence.begin(), search.evidence.end());
  if (*best < kMinSpeedScore) return std::nullopt;
  const std::size_t best_index = static_cast<std::size_t>(best - search.evidence.begin());
  const double centre = hypotheses[best_index];
  search.evidence_standstill = std::abs(centre) < kStandstillSpeed;
  search.unclear_speed.reset();
  // A speed waits until it leads its aliases clearly (kMinLeadOverAliases); at the search's time
  // limit the best is taken anyway (process).
  if (!search.evidence_standstill &&
      !stands_clear_of_aliases(hypotheses, search.evidence, best_index, kMinAliasSeparation, kMinLeadOverAliases)) {
    search.unclear_speed = centre;
    return std::nullopt;
  }
  // A standstill waits for the IMU to say the body is still (body_rocking.hpp): what moves with
  // the sensor scores a standstill best, and a car parked beside the road, seen through the window
  // the ego roof leaves, did so for the first two scans of a start at 12 m/s (highway seed 7: 41 m
  // ATE); by the fifth the true speed leads. While the body rocks, the search goes on; a car
  // rocked at rest (a door shut) keeps its standstill's lead, decided once the rocking ends or at
  // the time limit.
  if (search.evidence_standstill && motion != BodyMotion::kStill) {
    search.moving_peak.reset();
    if (const auto peak = separate_peak(hypotheses, search.evidence, kMinMovingPeakSpeed, kMinMovingPeakShare)) {
      search.moving_peak =
          refine_around([&](double speed) { return score_since_first(placement(speed), &StructurePoints::off_lines); },
                        hypotheses[*peak], speeds)
              .value;
    }
    return std::nullopt;
  }
  return refine_around([&](double speed) { return score_since_first(placement(speed), &StructurePoints::off_lines); },
                       centre, speeds)
      .value;
}

BodyMotion LidarInertialOdometry::body_motion_until(double time) const {
  BodyRockingParams params;
  params.gyro_noise_density = config_.imu.gyro_noise_density;
  return body_motion(imu_, time, config_.odometry.up_axis, params);
}

void LidarInertialOdometry::settle_gyro_bias_at_rest(double from, double to) {
  // The LiDAR has seen the body at rest from the first scan to this one, so the gyro's mean over
  // that time is its bias. The start-up alignment's window (the first scan's 0.1 s when the IMU
  // has just come up) may have caught the body rocking (someone climbing in) at a swing's peak:
  // 0.02 rad/s taken for a bias turned the heading 23 deg over the next 20 s on the approach to a
  // tunnel; over the whole rest the swings cancel.
  if (const auto rate = mean_angular_rate(imu_, from, to)) state_.gyro_bias = *rate;
}

void LidarInertialOdometry::trust_gyro_bias_measured_at_rest() {
  // At rest the gyro reads its bias (the alignment's mean, or the whole rest's when the body
  // rocked), to its noise over the rest. Left at the start's wide prior, the bias is what the
  // LiDAR teaches first, and moving off, when the standstill's keyframe is nearly all the map,
  // its ground planes turned the pose 0.3-0.8 deg a scan: the bias about the vertical followed
  // (-0.0043 -> -0.013 rad/s on tunnel seed 10) and the heading kept turning after the map had
  // grown (+16.5 deg; the noise-free twin +14.6 deg, 0.1 deg with the bias trusted).
  const double sd = config_.odometry.standstill_gyro_bias_std;
  covariance_.block<3, kStateDim>(9, 0).setZero();
  covariance_.block<kStateDim, 3>(0, 9).setZero();
  covariance_.block<3, 3>(9, 9) = Eigen::Matrix3d::Identity() * sd * sd;
}

void LidarInertialOdometry::start_at_speed(double speed) {
  state_.velocity = state_.rotation * (speed * config_.odometry.forward_axis);
  // Measured 1-2 % off on the highway (rails and barrier look alike at any speed; posts, lamps
  // and trees decide), closer in town. 0.2 m/s (trusting the map at once) turned the static start
  // on the highway from 5.6 m to 61 m ATE; with 0.5 the first scans are deskewed again and the map
  // restarts once the filter has the speed, as before.
  const double speed_std = 0.5;
  covariance_.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity() * speed_std * speed_std;
  hold_forward_accel_bias_ = std::abs(speed) > 2.0 * speed_std;  // moving for sure
  if (std::abs(speed) >= kStandstillSpeed) {
    // Under way, the gyro's mean over the start-up alignment was the body pitching and rolling (on
    // its springs, over the road's crests and banks) as much as its bias: highway seed 7 at 15 m/s
    // read 0.014 / -0.018 rad/s about x / y over its first 0.1 s for a bias of 0.002 / -0.005, and
    // the speed search's 2 s of IMU alone before the first keyframe tilted the pose 1.5 deg (3.38 m
    // ATE in 60 s). The bias prior's zero is nearer; the LiDAR teaches the rest. About the up axis
    // a car turns only with the road, and a straight start reads the bias there.
    const Eigen::Vector3d up = config_.odometry.up_axis.normalized();
    state_.gyro_bias = up * up.dot(state_.gyro_bias);
  }
  covariance_.block<3, 3>(6, 0).setZero();
  covariance_.block<3, 3>(0, 6).setZero();
}

void LidarInertialOdometry::process_scan(const Scan& scan, const ScanFeatures* extracted, OdometryResult& result) {
  const double t_end = scan_end_time(scan);

  auto t = Clock::now();
  const NavState start = state_;
  auto intervals = imu_intervals(imu_, start.time, t_end);
  const auto gaps = imu_gaps(imu_, start.time, t_end, config_.imu.max_gap_s);
  if (!gaps.empty()) {
    result.status |= kStatusImuGap;
    bridge_imu_gaps(intervals, gaps, start, last_angular_rate_, start.gravity);
  }
  ImuPreintegration preintegration(start.gyro_bias, start.accel_bias, noise_);
  for (const auto& iv : intervals) preintegration.integrate(iv.gyro, iv.accel, iv.dt);
  NavState predicted = preintegration.predict(start, start.gravity);
  predicted.time = t_end;
  StateCovariance predicted_covariance = propagate_covariance(preintegration, start);
  if (!gaps.empty()) widen_for_imu_gaps(predicted_covariance, gaps);
  PoseTable relative = deskew_trajectory(scan, start, predicted, intervals);
  result.deskew_ms = elapsed_ms(t);

  if (extracted == nullptr) {
    t = Clock::now();
    extractor_.extract(scan, scan_features_);
    result.features_ms = elapsed_ms(t);
  }
  const ScanFeatures& indices = extracted != nullptr ? *extracted : scan_features_;
  t = Clock::now();
  Features features;
  deskew_features(scan, indices, relative, features);
  result.deskew_ms += elapsed_ms(t);
  result.edge_features = features.edges.size();
  result.plane_features = features.planes.size();

  t = Clock::now();
  if (plane_map_.empty()) {
    state_ = predicted;
    covariance_ = predicted_covariance;
  } else {
    // Rolling start on a road without along-track structure (highway: smallest translation
    // eigenvalue 0.1-2, against ~400 in town): the first maps' ground rings pull each scan
    // towards the previous keyframes (a standstill) by 0.1-0.2 m a scan, and with nothing to
    // tell the two apart the filter took that as a forward accelerometer bias of 0.5-0.8 m/s^2
    // (the simulated one is -0.1) and the speed decayed through zero. So a rolling start, and any
    // scan after one that left the along-track position unconstrained (below), keeps the bias's
    // prior along the forward axis, the velocity taking the corrections meanwhile.
    result.forward_hold = hold_forward_accel_bias_;
    if (hold_forward_accel_bias_) hold_forward_acceleration(predicted_covariance, predicted, config_.odometry.forward_axis);
    // Moving off from a standstill, the map is the standstill's one keyframe, and its planes
    // (rail ends, the rings' short arcs on posts, on objects ahead and on the ground), seen from
    // that one viewpoint, pulled each scan back along the track: on the highway's ~150 residuals
    // a scan that outweighed the IMU, and 8 s static starts lost 0.05-0.11 m/s a scan and ran up
    // to 19 % short. Until the second keyframe walls locate the scan across the track only, and
    // the ground too once the body rolls (body_rocking.hpp): at rest the scans are the map's
    // viewpoint, and the ground's fine pattern holds the position where the walls let go
    // (30 s parked: 0.08 m ATE, 0.44 m with the ground blind as well). Edges and posts keep their
    // full pull (docs/odometry.md "Moving off").
    // The same one keyframe turned the heading too: a degree within a second of moving off inside a
    // tunnel (seeds 7 and 17), and the bias about the vertical followed by 4 mrad/s, four times
    // the std it was given at rest, so the heading went on turning after the map had grown (tunnel
    // seed 17 3.66 m ATE, seeds 1-20 30.4 m summed; held: 1.76 m, 26.9 m; docs/odometry.md,
    // 2026-12-06, seventh session). The gyro measured that bias at rest; until the car has left
    // the standstill's map, the LiDAR does not teach it.
    UpdateParams params = update_params_;
    if (moving_off_) {
      params.planes_blind_along_body = config_.odometry.forward_axis;
      params.ground_blind_too = body_motion_until(t_end) == BodyMotion::kRocking;
      hold_yaw_rate_bias(predicted_covariance, config_.odometry.up_axis);
    }
    UpdateResult update = iterated_update(predicted, predicted_covariance, features.planes, plane_map_, features.edges,
                                          edge_map_, params, &post_axis_map_);
    if (velocity_std(predicted_covariance) > kTrustedVelocityStd && config_.odometry.deskew == DeskewMode::kImu) {
      // Rolling start: the deskew above assumed the prior speed. Re-deskew with the speed the
      // LiDAR just measured (start velocity implied by the updated end state) and update again.
      NavState corrected_start = start;
      corrected_start.velocity = update.state.velocity - update.state.gravity * preintegration.duration() -
                                 start.rotation * preintegration.delta_velocity(start.gyro_bias, start.accel_bias);
      relative = deskew_trajectory(scan, corrected_start, preintegration.predict(corrected_start, corrected_start.gravity), intervals);
      deskew_features(scan, indices, relative, features);
      update = iterated_update(predicted, predicted_covariance, features.planes, plane_map_, features.edges, edge_map_,
                               params, &post_axis_map_);
    }
    // Hysteresis: a held bias is released only by a scan well above the threshold. Under a
    // gantry the eigenvalue swings about it scan by scan, and each scan just above let one
    // scan's along-track pull into the bias (noise-free highway seeds 7 / 8: 791 / 3.37 m ATE;
    // released at 2x: 0.33 / 0.06 m; docs/odometry.md, 2026-12-06, second session).
    const double hold_threshold = config_.odometry.degeneracy_eigenvalue *
                                  (result.forward_hold ? config_.odometry.hold_release_eigenvalue_factor : 1.0);
    const bool below_hold_threshold = update.min_translation_eigenvalue < hold_threshold;
    const bool turning = turning_faster_than(start, predicted, update.state, preintegration.duration(),
                                             config_.odometry.hold_release_yaw_rate_deg_s);
    // An IMU that contradicts the LiDAR far beyond its own covariance (a clock step, a sensor
    // gone wrong) must not teach the biases and gravity: they would carry its error on, into the
    // degenerate stretches where nothing corrects them. The scan's pose then comes from the LiDAR.
    scans_since_imu_inconsistent_ = std::min(scans_since_imu_inconsistent_ + 1, kConsistentScansToRelease);  // no overflow in a long run
    if (prediction_nis(update.state, predicted, predicted_covariance) > config_.odometry.max_prediction_nis) {
      hold_imu_states(predicted_covariance);
      update = iterated_update(predicted, predicted_covariance, features.planes, plane_map_, features.edges, edge_map_,
                               params, &post_axis_map_);
      ++inconsistent_imu_scans_;
      scans_since_imu_inconsistent_ = 0;
      result.status |= kStatusImuInconsistent;
    }
    // Highway, tunnel, and the first metres of a static start, whose map of the standstill pulls
    // the scans back (highway seed 1, 60 s, static start: 6.25 -> 0.43 m ATE; docs/odometry.md).
    // But not through a turn: the bias lives in the body and the tilt in the world, so a heading
    // change separates them, and a split held from before the turn puts their mismatch (up to 0.08
    // m/s^2 on tunnel s1) into the speed (tunnel drives 1.85-3.63 -> 0.75-1.65 m ATE). Only while
    // the IMU has agreed with the LiDAR for a while: a clock-stepped IMU turns where the car does not.
    hold_forward_accel_bias_ =
        below_hold_threshold && !(turning && scans_since_imu_inconsistent_ >= kConsistentScansToRelease);
    state_ = update.state;
    state_.time = t_end;
    covariance_ = update.covariance;
    result.velocity_correction_body = state_.rotation.transpose() * (state_.velocity - predicted.velocity);
    const Eigen::Vector3d forward = config_.odometry.forward_axis.normalized();
    if (!result.forward_hold) {
      held_bias_trim_.reset();
    } else if (const auto trim = held_bias_trim_.add_held_scan(forward.dot(result.velocity_correction_body),
                                                               preintegration.duration())) {
      state_.accel_bias += forward * *trim;
    }
    result.residuals = update.residuals;
    result.iterations = update.iterations;
    result.rms_residual_m = update.rms_residual_m;
    result.min_translation_eigenvalue = update.min_translation_eigenvalue;
    if (update.degenerate_directions > 0) result.status |= kStatusDegenerate;
    if (update.residuals < 50) result.status |= kStatusFewFeatures;
  }
  result.registration_ms = elapsed_ms(t);
  if (preintegration.duration() > 0.0) {
    last_angular_rate_ = so3::log(start.rotation.transpose() * state_.rotation) / preintegration.duration();
  }

  t = Clock::now();
  // The first keyframes of a rolling start were deskewed with an unknown speed: once the speed
  // is known, start the map afresh from the current, correctly deskewed scan.
  if (!map_trusted_ && velocity_std(covariance_) < kTrustedVelocityStd) {
    map_trusted_ = true;
    keyframes_.clear();
    plane_map_ = LocalMap(config_.odometry.map_voxel_m, config_.odometry.map_points_per_voxel,
                          config_.odometry.map_min_point_spacing_m);
    edge_map_ = plane_map_;
    post_axis_map_ = plane_map_;
  }
  if (config_.odometry.beam_calibration && map_trusted_ && !plane_map_.empty()) learn_beam_calibration(features);
  consider_keyframe(features, result);
  // Two keyframes a metre or two apart still leave most ground voxels beyond 10 m with one ring's
  // arc (rings lie 1-5 m apart on the road at 10-20 m): their planes pull the scans back towards
  // where the car stood. In a tunnel of constant section nothing else locates the car along it,
  // and that pull stopped a car pulling away at 1.6 m/s^2 within 15 s (tunnel seed 9: 4638 m ATE
  // ended at the 2nd keyframe, 1.14 m at 10 m; docs/odometry.md "Ten tunnel seeds").
  if (moving_off_ && keyframes_.size() >= 2 &&
      (state_.position - standstill_position_).norm() >= config_.odometry.move_off_distance_m) {
    moving_off_ = false;
  }
  result.map_ms = elapsed_ms(t);

  while (imu_.size() > 2 && imu_[1].time < state_.time - 0.5) imu_.pop_front();
  result.state = state_;
  result.covariance = covariance_;
}

void LidarInertialOdometry::consider_keyframe(const Features& features, OdometryResult& result) {
  // A scan too poor to register on the map (blinded or garbage returns) has nothing to add to it
  // either; as a keyframe it would only push good keyframes out of the window.
  if (result.status & kStatusFewFeatures) return;
  const auto& o = config_.odometry;
  if (keyframes_.empty()) {
    add_keyframe(features, similarity_cloud(features));
    result.status |= kStatusKeyframe;
    return;
  }
  const NavState& last = keyframes_.back().state;
  const double distance = (state_.position - last.position).norm();
  const double angle = so3::log(last.rotation.transpose() * state_.rotation).norm();
  if (distance < o.keyframe_distance_m && angle < o.keyframe_angle_deg * kDegToRad) return;
  std::vector<Eigen::Vector3d> cloud = similarity_cloud(features);
  if (o.keyframe_gating == KeyframeGating::kHausdorff) {
    result.hausdorff_m = hausdorff_distance(cloud, keyframes_.back().similarity_cloud_world, 4.0 * o.hausdorff_threshold_m);
    if (result.hausdorff_m <= o.hausdorff_threshold_m) return;
  }
  add_keyframe(features, std::move(cloud));
  result.status |= kStatusKeyframe;
}

std::vector<Eigen::Vector3d> LidarInertialOdometry::similarity_cloud(const Features& features) const {
  std::vector<Eigen::Vector3d> cloud = transformed(features.planes, state_);
  const auto edges = transformed(features.edges, state_);
  cloud.insert(cloud.end(), edges.begin(), edges.end());
  return voxel_downsample(cloud, config_.odometry.hausdorff_voxel_m);
}

void LidarInertialOdometry::add_keyframe(const Features& features, std::vector<Eigen::Vector3d> similarity_cloud_world) {
  // Only the newest keyframe's similarity cloud is read (the next candidate's Hausdorff test, the
  // backend's copy): the window's older ones let theirs go (with 200 keyframes, 8x the memory).
  if (!keyframes_.empty()) {
    keyframes_.back().similarity_cloud_world.clear();
    keyframes_.back().similarity_cloud_world.shrink_to_fit();
  }
  Keyframe kf;
  kf.id = next_keyframe_id_++;
  kf.state = state_;
  kf.planes_world = transformed(features.map_planes, state_);
  kf.edges_world = transformed(features.edges, state_);
  kf.similarity_cloud_world = std::move(similarity_cloud_world);
  plane_map_.add(kf.planes_world, kf.id);
  edge_map_.add(kf.edges_world, kf.id);
  if (update_params_.posts) {
    kf.post_axes_world = post_axes(kf.edges_world, state_.to_world(*update_params_.edge_viewpoint_body),
                                   -state_.gravity.normalized(), update_params_.posts->depth_m);
    post_axis_map_.add(kf.post_axes_world, kf.id);
  }
  keyframes_.push_back(std::move(kf));
  while (keyframes_.size() > static_cast<std::size_t>(config_.odometry.window_keyframes)) {
    const Keyframe& oldest = keyframes_.front();
    plane_map_.remove_keyframe(oldest.planes_world, oldest.id);
    edge_map_.remove_keyframe(oldest.edges_world, oldest.id);
    post_axis_map_.remove_keyframe(oldest.post_axes_world, oldest.id);
    keyframes_.pop_front();
  }
}

}  // namespace liod
