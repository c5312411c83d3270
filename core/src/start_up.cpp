#include "liod/start_up.hpp"

#include <algorithm>
#include <cmath>

#include "liod/angles.hpp"
#include "liod/gravity_alignment.hpp"
#include "liod/reinitialization.hpp"
#include "liod/speed_search.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace {

// Farther returns add little to the speed search but the gyro's error, which grows with range.
constexpr double kStructureRange_m = 80.0;
constexpr double kStructureVoxel_m = 0.1;    // thinning of the structure points (3-D)
// A footprint matches within this: thin posts are ~10 cm across, and the fine speed step moves a
// point 5 mm per scan period.
constexpr double kFootprintRadius_m = 0.12;
constexpr double kMinSpeedScore = 20.0;      // about as many structure points matched (a pair, or all summed)
// A scan's structure is scored against this many scans before it: a post passes a sensor-locked
// window within a few scans, and the cost per hypothesis grows with the points held.
constexpr std::size_t kSpeedSearchMemory = 4;
// At most this many structure points per scan off the rails: each hypothesis places and indexes
// the union anew, and a dense town scan holds thousands (sparse roads 15-40).
constexpr std::size_t kMaxSearchPointsPerScan = 2500;
// Without enough structure off the rails for this long, the first scans' standstill stands if
// they saw one, else the speed is left to the LiDAR's registration under the wide prior.
constexpr double kMaxSpeedSearch_s = 2.0;
// The speed with all of the structure is decided on this scan (0 the first), from its overlap
// and that of each scan before it with their predecessors, summed: from the first pair alone a
// regular spacing of posts aliases (docs/design.md, "Start-up: alignment and the rolling start's speed search").
constexpr std::size_t kAllStructureScans = 2;
// Below this a speed is a standstill (the rails' footprints move with the sensor and vote for one).
constexpr double kStandstillSpeed = 1.0;
// The rails-free search's best speed must lead every other peak at least kMinAliasSeparation
// from it by kMinLeadOverAliases (stands_clear_of_aliases): posts at a spacing s place an alias at
// v - s / (k T) for each scan k back, and for a scan or two an alias can lead by a few per cent.
constexpr double kMinAliasSeparation = 2.0;
constexpr double kMinLeadOverAliases = 1.3;
// A standstill's evidence falls off to either side of zero and is on its shoulder still at this
// speed; a moving car whose rings cut a rail in spots fixed in the sensor's frame scores a
// standstill too, but its true speed also peaks on its own, at more than this share.
constexpr double kMinMovingPeakSpeed = 3.0;
constexpr double kMinMovingPeakShare = 0.5;
// The speed search's result is 1-2 % off on a highway (rails and barriers look alike at any
// speed; posts, lamps and trees decide), closer in town: its 1 sigma.
constexpr double kFoundSpeedStd = 0.5;

GridSearchParams speed_grid() {
  GridSearchParams speeds;
  speeds.min = -10.0;  // reversing
  speeds.max = 50.0;
  speeds.coarse_step = 0.5;
  speeds.fine_step = 0.05;
  return speeds;
}

}  // namespace

// Each hypothesis (a speed along the forward axis at the first scan: a car does not slide
// sideways) deskews the held scans with the IMU and places them in one frame.
class SpeedHypotheses {
 public:
  using Points = std::vector<StartUp::TimedPoint> StartUp::StructurePoints::*;

  SpeedHypotheses(const NavState& base, std::vector<ImuInterval> intervals, const Eigen::Vector3d& forward_axis,
                  const std::vector<StartUp::StructurePoints>& structure)
      : base_(base), intervals_(std::move(intervals)), forward_axis_(forward_axis), structure_(structure) {}

  const std::vector<StartUp::StructurePoints>& structure() const { return structure_; }

  PoseTable placement(double speed) const {
    NavState start = base_;
    start.velocity = base_.rotation * (speed * forward_axis_);
    return integrate_imu_poses(start, intervals_, base_.gravity);
  }

  // The overlap of scan k with the kSpeedSearchMemory scans before it, each placed by one
  // hypothesis's poses. Not with scan k - 1 alone: where a ring passes below a guard rail only in
  // a window fixed in the sensor's frame, consecutive scans see different posts, and a speed that
  // moves each post onto the next one's place in the scan before overlaps as well as the true
  // one. Only the true speed also lands a post on itself seen two or more scans before.
  double score_against_earlier(const PoseTable& world, std::size_t k, Points points) const {
    std::vector<Eigen::Vector3d> earlier;
    for (std::size_t j = k > kSpeedSearchMemory ? k - kSpeedSearchMemory : 0; j < k; ++j) {
      const auto placed_j = placed(structure_[j].*points, world);
      earlier.insert(earlier.end(), placed_j.begin(), placed_j.end());
    }
    return FootprintOverlap(earlier, kFootprintRadius_m).score(placed(structure_[k].*points, world));
  }

  // Every scan's overlap with those before it, all placed by one hypothesis's poses.
  double score_since_first(double speed, Points points) const {
    const PoseTable world = placement(speed);
    double sum = 0.0;
    for (std::size_t k = 1; k < structure_.size(); ++k) sum += score_against_earlier(world, k, points);
    return sum;
  }

  // Adds to each grid hypothesis's evidence the newest scan's overlap with those before it.
  void add_newest_scan(const std::vector<double>& grid, Points points, std::vector<double>& evidence) const {
    const std::size_t newest = structure_.size() - 1;
    evidence.resize(grid.size(), 0.0);
    for (std::size_t i = 0; i < grid.size(); ++i) evidence[i] += score_against_earlier(placement(grid[i]), newest, points);
  }

  GridSearchResult refine(double centre, Points points) const {
    return refine_around([&](double speed) { return score_since_first(speed, points); }, centre, speed_grid());
  }

 private:
  static std::vector<Eigen::Vector3d> placed(const std::vector<StartUp::TimedPoint>& points, const PoseTable& world) {
    std::vector<Eigen::Vector3d> out;
    out.reserve(points.size());
    for (const auto& p : points) out.push_back(world.at(p.time) * p.body);
    return out;
  }

  const NavState& base_;
  std::vector<ImuInterval> intervals_;
  Eigen::Vector3d forward_axis_;
  const std::vector<StartUp::StructurePoints>& structure_;
};

bool StartDecision::standstill() const { return speed && std::abs(*speed) < kStandstillSpeed; }

StartUp::StartUp(const StartUpConfig& config) : config_(config) {
  rocking_.gyro_noise_density = config.gyro_noise_density;
}

bool StartUp::begin(const Scan& scan, const ImuBuffer& imu, NavState& state, StateCovariance& covariance,
                    const std::optional<NavState>& resume_from) {
  const double t_start = scan.start_time + config_.lidar_time_offset_s;
  const auto alignment = align_gravity(imu.samples(), t_start - 1.0, scan_end(scan));
  if (!alignment) return false;
  state = NavState{};
  state.time = t_start;
  state.rotation = alignment->rotation;
  state.gyro_bias = alignment->gyro_bias;
  state.gravity = Eigen::Vector3d(0.0, 0.0, -config_.gravity_m_s2);
  if (resume_from) state = placed_at(state, *resume_from, imu.samples());
  covariance.setZero();
  const double tilt = config_.tilt_std_deg * kDegToRad;
  covariance.diagonal().segment<3>(0) << tilt * tilt, tilt * tilt, 1e-6;  // yaw defines the world frame
  covariance.diagonal().segment<3>(3).setConstant(1e-6);                    // so does the origin
  covariance.diagonal().segment<3>(6).setConstant(config_.velocity_std * config_.velocity_std);
  // The speed, unknown even at rest, is searched for from the next scan on.
  search_ = SpeedSearch{};
  search_->first_end_time = scan_end(scan);
  search_->held.push_back(scan);
  search_->structure.push_back(vertical_structure_points(scan, state));
  covariance.diagonal().segment<3>(9).setConstant(config_.gyro_bias_std * config_.gyro_bias_std);
  covariance.diagonal().segment<3>(12).setConstant(config_.accel_bias_std * config_.accel_bias_std);
  // The alignment's tilt error is the accelerometer bias over g: as likely as the bias itself.
  const double gravity_tilt = config_.accel_bias_std / config_.gravity_m_s2;
  covariance.diagonal().segment<2>(kGravityIndex).setConstant(gravity_tilt * gravity_tilt);
  return true;
}

double StartUp::held_until() const { return scan_end(search_->held.back()); }

BodyMotion StartUp::body_motion_until(const ImuBuffer& imu, double time) const {
  return body_motion(imu.samples(), time, config_.up_axis, rocking_);
}

std::optional<StartDecision> StartUp::add_scan(const Scan& scan, const ImuBuffer& imu, const NavState& base) {
  SpeedSearch& search = *search_;
  const double end = scan_end(scan);
  // Over an IMU gap the hypotheses' placements would rest on a held sample: decide without it.
  const bool imu_gap = !imu.gaps(base.time, end, config_.max_imu_gap_s).empty();
  const bool timed_out = end - search.first_end_time >= kMaxSpeedSearch_s;
  const BodyMotion motion = body_motion_until(imu, end);
  if (motion == BodyMotion::kRocking) search.rocked = true;
  std::optional<double> speed;
  if (!imu_gap && !timed_out) speed = search_speed(scan, motion, imu, base);
  if (!speed && !imu_gap && !timed_out) {
    search.held.push_back(scan);
    return std::nullopt;
  }
  // Known at last, or not to be known: then first scans that saw a standstill in all of their
  // structure are taken at their word (a car waiting beside a rail) unless the body rocks on its
  // springs (body_rocking.hpp), else the wide prior stays and the LiDAR decides. A rocking body
  // overrules the first scans' standstill, which may be the rails' (a moving car's first scans
  // between rails see one too). Still rocking at the end, with a speed that peaks on its own
  // beside the standstill: the body rocks because the car rolls.
  if (!speed && search.evidence_standstill) speed = search.moving_peak;
  // A moving speed still short of a clear lead over its aliases is better than none: the LiDAR
  // alone under the wide prior does not find a highway's speed.
  if (!speed) speed = search.unclear_speed;
  if (!speed && (search.evidence_standstill || (search.all_structure_standstill && motion != BodyMotion::kRocking))) {
    speed = 0.0;
  }
  StartDecision decision{speed, search.rocked, std::move(search.held)};
  search_.reset();
  return decision;
}

bool StartUp::start_at_speed(double speed, NavState& state, StateCovariance& covariance) const {
  state.velocity = state.rotation * (speed * config_.forward_axis);
  covariance.block<3, 3>(6, 6) = Eigen::Matrix3d::Identity() * kFoundSpeedStd * kFoundSpeedStd;
  const bool hold_forward = std::abs(speed) > 2.0 * kFoundSpeedStd;  // moving for sure
  if (std::abs(speed) >= kStandstillSpeed) {
    // Under way, the gyro's mean over the start-up alignment was the body pitching and rolling (on
    // its springs, over the road's crests and banks) as much as its bias, and the IMU alone
    // carries the pose through the search: the bias prior's zero is nearer, and the LiDAR teaches
    // the rest. About the up axis a car turns only with the road, and a straight start reads the
    // bias there.
    const Eigen::Vector3d up = config_.up_axis.normalized();
    state.gyro_bias = up * up.dot(state.gyro_bias);
  }
  covariance.block<3, 3>(6, 0).setZero();
  covariance.block<3, 3>(0, 6).setZero();
  return hold_forward;
}

void StartUp::settle_at_rest(const StartDecision& decision, double end, const ImuBuffer& imu, NavState& state,
                             StateCovariance& covariance) const {
  // The LiDAR has seen the body at rest from the first scan to this one, so the gyro's mean over
  // that time is its bias. The alignment's window (the first scan's 0.1 s) may have caught a body
  // that rocked (someone climbing in) at a swing's peak; over the whole rest the swings cancel.
  if (decision.rocked) {
    const double from = decision.held.front().start_time + config_.lidar_time_offset_s;
    if (const auto rate = mean_angular_rate(imu.samples(), from, end)) state.gyro_bias = *rate;
  }
  // At rest the gyro reads its bias to its noise over the rest. Left at the start's wide prior,
  // the bias is what the LiDAR teaches first while moving off, when the standstill's keyframe is
  // nearly all the map and its planes turn the pose: the heading then keeps turning after the
  // map has grown.
  const double sd = config_.standstill_gyro_bias_std;
  covariance.block<3, kStateDim>(9, 0).setZero();
  covariance.block<kStateDim, 3>(0, 9).setZero();
  covariance.block<3, 3>(9, 9) = Eigen::Matrix3d::Identity() * sd * sd;
}

StartUp::StructurePoints StartUp::vertical_structure_points(const Scan& scan, const NavState& base) const {
  const double t0 = scan.start_time + config_.lidar_time_offset_s;
  std::vector<TimedPoint> candidates;
  std::vector<Eigen::Vector3d> levelled;  // the motion blur does not change what is vertical
  candidates.reserve(scan.points.size());
  levelled.reserve(scan.points.size());
  for (const auto& p : scan.points) {
    const Eigen::Vector3f sensor(p.x, p.y, p.z);
    const double range = sensor.norm();
    if (!(range >= config_.min_range_m && range <= kStructureRange_m) || !std::isfinite(p.time)) continue;  // NaN too
    if (config_.self_crop && config_.self_crop->contains(sensor)) continue;  // the car's own body: a standstill
    const Eigen::Vector3d body = config_.lidar_to_imu * sensor.cast<double>();
    candidates.push_back({t0 + static_cast<double>(p.time), body});
    levelled.push_back(base.rotation * body);
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
    const std::size_t stride =
        std::max<std::size_t>((indices.size() + kMaxSearchPointsPerScan - 1) / kMaxSearchPointsPerScan, 1);
    for (std::size_t k = 0; k < indices.size(); k += stride) out.push_back(candidates[thinned[indices[k]]]);
  };
  StructurePoints out;
  std::vector<std::size_t> every(thinned.size());
  for (std::size_t k = 0; k < every.size(); ++k) every[k] = k;
  within_budget(every, out.all);
  const Eigen::Vector3d forward = base.rotation * config_.forward_axis;
  within_budget(off_along_track_lines(thinned_levelled, forward.head<2>(), AlongTrackLineParams{}), out.off_lines);
  return out;
}

std::optional<double> StartUp::search_speed(const Scan& scan, BodyMotion motion, const ImuBuffer& imu,
                                            const NavState& base) {
  // Their vertical structure is compared from above (speed_search.hpp explains why not the
  // ground, and why not a local registration).
  auto intervals = imu_intervals(imu.samples(), base.time, scan_end(scan));
  if (intervals.empty()) return std::nullopt;
  search_->structure.push_back(vertical_structure_points(scan, base));
  const SpeedHypotheses hypotheses(base, std::move(intervals), config_.forward_axis, search_->structure);
  if (search_->structure.size() - 1 <= kAllStructureScans) {
    if (const auto speed = speed_from_all_structure(hypotheses)) return speed;
  }
  return speed_off_the_rails(hypotheses, motion);
}

// All the structure: the rails along a road, their posts and ends, tell the speed of a moving
// vehicle best, but vote for a standstill at rest and beside a rail alike.
std::optional<double> StartUp::speed_from_all_structure(const SpeedHypotheses& hypotheses) {
  SpeedSearch& search = *search_;
  const std::vector<double> grid = coarse_grid(speed_grid());
  const std::size_t newest = search.structure.size() - 1;
  hypotheses.add_newest_scan(grid, &StructurePoints::all, search.evidence_all);
  if (newest != kAllStructureScans) return std::nullopt;
  const auto best = std::max_element(search.evidence_all.begin(), search.evidence_all.end());
  const GridSearchResult found =
      hypotheses.refine(grid[static_cast<std::size_t>(best - search.evidence_all.begin())], &StructurePoints::all);
  if (found.score < kMinSpeedScore) return std::nullopt;
  if (std::abs(found.value) >= kStandstillSpeed) return found.value;
  search.all_structure_standstill = true;
  return std::nullopt;
}

// A standstill, or not enough to tell: the rails' footprints move with the sensor and vote for a
// standstill that may not be (off_along_track_lines), so without them, and summed over the scans
// until enough structure has passed (one scan on a highway often holds a post or two).
std::optional<double> StartUp::speed_off_the_rails(const SpeedHypotheses& hypotheses, BodyMotion motion) {
  SpeedSearch& search = *search_;
  const std::vector<double> grid = coarse_grid(speed_grid());
  const std::size_t newest = search.structure.size() - 1;
  hypotheses.add_newest_scan(grid, &StructurePoints::off_lines, search.evidence);
  if (newest < kAllStructureScans) return std::nullopt;
  const auto best = std::max_element(search.evidence.begin(), search.evidence.end());
  if (*best < kMinSpeedScore) return std::nullopt;
  const std::size_t best_index = static_cast<std::size_t>(best - search.evidence.begin());
  const double centre = grid[best_index];
  search.evidence_standstill = std::abs(centre) < kStandstillSpeed;
  search.unclear_speed.reset();
  // A speed waits until it leads its aliases clearly; at the search's time limit the best is
  // taken anyway (add_scan).
  if (!search.evidence_standstill &&
      !stands_clear_of_aliases(grid, search.evidence, best_index, kMinAliasSeparation, kMinLeadOverAliases)) {
    search.unclear_speed = centre;
    return std::nullopt;
  }
  // A standstill waits for the IMU to say the body is still (body_rocking.hpp): what moves with
  // the sensor scores a standstill best (a car parked beside the road, seen through the window
  // the ego roof leaves), while the true speed of a moving car comes to lead within a few scans.
  // A car rocked at rest (a door shut) keeps its standstill's lead, decided once the rocking ends
  // or at the time limit.
  if (search.evidence_standstill && motion != BodyMotion::kStill) {
    search.moving_peak.reset();
    if (const auto peak = separate_peak(grid, search.evidence, kMinMovingPeakSpeed, kMinMovingPeakShare)) {
      search.moving_peak = hypotheses.refine(grid[*peak], &StructurePoints::off_lines).value;
    }
    return std::nullopt;
  }
  return hypotheses.refine(centre, &StructurePoints::off_lines).value;
}

}  // namespace liod
