#pragma once
// The front end's start: the attitude from gravity, then the speed. A vehicle may be standing or
// already under way when liod starts (a restart on the road). The IMU gives the attitude (gravity)
// and the turn (gyro) but not the speed, and a wrong speed deskews and places every early scan
// wrongly. So the first scans are held, not registered, while the speed search (speed_search.hpp)
// finds the speed along the vehicle's forward axis under which their vertical structure lands on
// itself; a standstill also measures the gyro's bias at rest (the IMU reads its bias there).

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "liod/body_rocking.hpp"
#include "liod/curvature_features.hpp"
#include "liod/error_state.hpp"
#include "liod/imu_buffer.hpp"
#include "liod/imu_trajectory.hpp"
#include "liod/types.hpp"

namespace liod {

struct StartUpConfig {
  Eigen::Vector3d forward_axis = Eigen::Vector3d::UnitX();  // body frame: a car moves along it
  Eigen::Vector3d up_axis = Eigen::Vector3d::UnitZ();
  Pose lidar_to_imu;
  double lidar_time_offset_s = 0.0;
  double min_range_m = 2.0;             // nearer returns are not used
  std::optional<CropBox> self_crop;     // returns of the vehicle itself
  double gyro_noise_density = 5.0e-4;   // rad/s/sqrt(Hz): what the gyro spreads at rest
  double max_imu_gap_s = 0.05;
  double gravity_m_s2 = 9.80665;
  // Priors of the first state (1 sigma).
  double tilt_std_deg = 5.0;            // roll and pitch from the first accelerometer readings
  double velocity_std = 20.0;           // m/s: the vehicle may be under way
  double gyro_bias_std = 0.01;          // rad/s
  double accel_bias_std = 0.2;          // m/s^2
  double standstill_gyro_bias_std = 0.001;  // rad/s: the bias a standstill measured at rest
};

class SpeedHypotheses;  // start_up.cpp

/// What the start decided once the speed is known, or cannot be.
struct StartDecision {
  std::optional<double> speed;  // along the forward axis at the first scan; none: left to the LiDAR
  bool rocked = false;          // the body rocked on its springs while the search went on
  std::vector<Scan> held;       // the scans before the deciding one
  bool standstill() const;
};

class StartUp {
 public:
  explicit StartUp(const StartUpConfig& config);

  /// The first scan: the attitude from the IMU around it, the priors, and the search begins.
  /// False while the IMU cannot tell the attitude yet. With `resume_from` (the last plausible
  /// state before a restart) the attitude, gravity, biases and position are that state's, carried
  /// to the scan by the gyro (placed_at): the IMU's last second may hold what made the state
  /// implausible, and levelling under way tilts by the acceleration.
  bool begin(const Scan& scan, const ImuBuffer& imu, NavState& state, StateCovariance& covariance,
             const std::optional<NavState>& resume_from = std::nullopt);
  bool searching() const { return search_.has_value(); }
  /// The newest held scan's end (IMU clock), while searching.
  double held_until() const;
  void abandon() { search_.reset(); }

  /// A scan while searching, `base` the first scan's state: the decision once it is made (the
  /// search ends), else the scan is held.
  std::optional<StartDecision> add_scan(const Scan& scan, const ImuBuffer& imu, const NavState& base);

  /// Under way at `speed`: the velocity and its covariance, and the gyro bias's start (below).
  /// Returns whether the forward accelerometer bias is to be held (moving for sure).
  bool start_at_speed(double speed, NavState& state, StateCovariance& covariance) const;
  /// A standstill: the gyro bias as measured at rest (over the whole rest if the body rocked),
  /// trusted to standstill_gyro_bias_std. `end`: the deciding scan's end.
  void settle_at_rest(const StartDecision& decision, double end, const ImuBuffer& imu, NavState& state,
                      StateCovariance& covariance) const;

  /// What the gyro's roll-and-pitch rocking says of the motion up to `time` (body_rocking.hpp).
  BodyMotion body_motion_until(const ImuBuffer& imu, double time) const;

  struct TimedPoint {
    double time;           // IMU clock
    Eigen::Vector3d body;  // IMU frame at that time
  };
  struct StructurePoints {
    std::vector<TimedPoint> all;        // vertical structure (speed_search.hpp), thinned
    std::vector<TimedPoint> off_lines;  // without the rails and barriers along the road
  };

 private:
  // The search's evidence: the held scans' structure points, and the overlap of each with those
  // before it, summed per speed hypothesis (start_up.cpp explains the two kinds).
  struct SpeedSearch {
    double first_end_time = 0.0;
    bool all_structure_standstill = false;  // the first scans' best speed with all of the structure, a standstill
    bool evidence_standstill = false;       // the best speed off the rails so far, a standstill
    bool rocked = false;                    // the IMU saw the body rock while the search went on
    std::optional<double> moving_peak;      // while the body rocks: a second peak of that evidence
    std::optional<double> unclear_speed;    // that evidence's best speed while it does not stand clear of its aliases
    std::vector<Scan> held;                 // every scan since the first
    std::vector<StructurePoints> structure;
    std::vector<double> evidence;           // off the rails, from the second scan on
    std::vector<double> evidence_all;       // all of the structure, over the first scans
  };
  double scan_end(const Scan& scan) const { return scan.end_time + config_.lidar_time_offset_s; }
  StructurePoints vertical_structure_points(const Scan& scan, const NavState& base) const;
  std::optional<double> search_speed(const Scan& scan, BodyMotion motion, const ImuBuffer& imu, const NavState& base);
  std::optional<double> speed_from_all_structure(const SpeedHypotheses& hypotheses);
  std::optional<double> speed_off_the_rails(const SpeedHypotheses& hypotheses, BodyMotion motion);

  StartUpConfig config_;
  BodyRockingParams rocking_;
  std::optional<SpeedSearch> search_;
};

}  // namespace liod
