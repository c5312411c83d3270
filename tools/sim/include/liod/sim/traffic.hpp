#pragma once
// Other road users (liod-sim --traffic): cars, vans and trucks driving the lanes of the drive's
// road at speeds of their own, slowing for bends and some stopping at junctions. Oncoming traffic
// drives the opposite lanes; in the drive's own lane vehicles run ahead of the car (and one or two
// behind it), never closer than a time gap; on a dual carriageway the other lane carries vehicles
// that pass the car or are passed. A vehicle's motion is sampled every 50 ms and interpolated, and
// each laser firing sees every vehicle where it is at that firing's time.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "liod/sim/path.hpp"
#include "liod/sim/terrain.hpp"
#include "liod/sim/trajectory.hpp"
#include "liod/sim/world.hpp"

namespace liod::sim {

/// A box that moves with a vehicle: where it is at the firing's start, and its velocity.
struct MovingBox {
  Box box;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
};

struct TrafficVehicle {
  std::uint32_t lane = 0;
  double half_length = 2.2;
  double half_width = 0.9;
  double top = 0.0;  // 0: a car with a glass cabin, else a van or truck this tall
  Appearance paint;
  std::vector<float> s;  // metres along its lane at t = k * kTrafficStep
};

inline constexpr double kTrafficStep = 0.05;  // s

class Traffic {
 public:
  /// Traffic on the road of `plan` (which must describe its lanes) around the car driving
  /// `ego` for `duration` seconds; vehicles whose path would ever touch the car are left out.
  Traffic(const DrivePlan& plan, const Trajectory& ego, const Terrain& terrain, double duration,
          std::uint64_t seed);

  std::size_t size() const { return vehicles_.size(); }
  const TrafficVehicle& vehicle(std::size_t i) const { return vehicles_[i]; }
  /// Where vehicle i is at time t (its centre on the ground, unit heading, speed); false when it
  /// is not on the road.
  bool place(std::size_t i, double t, Eigen::Vector2d& position, Eigen::Vector2d& heading,
             double& speed) const;
  /// Vehicles within `radius` of p at t0 or t1 (pad the radius by how far they move between).
  void near(double t0, double t1, const Eigen::Vector2d& p, double radius,
            std::vector<std::uint32_t>& ids) const;
  /// The boxes at time t of those of `ids` that a firing from `origin` whose beams leave within a
  /// few degrees of the horizontal direction `dir` can meet.
  void boxes_toward(const std::vector<std::uint32_t>& ids, double t, const Eigen::Vector2d& origin,
                    const Eigen::Vector2d& dir, std::vector<MovingBox>& out) const;
  /// Vehicle i's boxes at time t (none when it is not on the road).
  void boxes(std::size_t i, double t, std::vector<MovingBox>& out) const;

 private:
  struct Lane {
    std::vector<Eigen::Vector2d> points;  // 1 m apart
  };
  Eigen::Vector2d lane_point(const Lane& lane, double s) const;
  std::size_t build_lanes(const DrivePlan& plan);
  void populate(std::uint32_t lane, bool against, const DrivePlan& plan, const std::vector<float>& ego_s, Rng& rng);
  void leave_out_touching(const Trajectory& ego, double duration);

  Terrain terrain_;
  std::vector<Lane> lanes_;
  std::vector<TrafficVehicle> vehicles_;
};

/// One worker's traffic scratch for LidarModel::fire: the vehicles near the sensor during the
/// current revolution and the boxes a firing may meet.
struct TrafficScratch {
  const Traffic* traffic = nullptr;
  std::vector<std::uint32_t> near;
  std::vector<MovingBox> boxes;
};

/// The nearest of `boxes` (each moved on by dt seconds of its velocity) along the ray within
/// (0, best); true and `hit` set when one is met.
bool intersect_moving(const std::vector<MovingBox>& boxes, double dt, const Eigen::Vector3d& o,
                      const Eigen::Vector3d& d, double best, Rng& rng, RayHit& hit);

}  // namespace liod::sim
