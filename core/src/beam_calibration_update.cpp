#include "liod/beam_calibration_update.hpp"

#include <cmath>
#include <optional>
#include <vector>

namespace liod {
namespace {

// Ground is a plane within 26 deg of level; a residual beyond 10 cm is a wrong match, not a
// millimetre beam offset. Beams below the horizon only, 8 m away or more: nearer, an offset moves
// a point by under a millimetre (range * offset), and what matters is the far ground.
constexpr double kGroundNormalCos = 0.9;
constexpr double kBeamResidualGateM = 0.1;
constexpr double kBeamMinRangeM = 8.0;
constexpr double kBeamMaxElevationRad = -0.01;
// Every 4th of those per beam: the offsets are constant, the sums keep ~1000 scans, and the
// search for each point's plane costs time (the calibration's share of a scan: docs/design.md).
constexpr std::uint32_t kBeamPointStride = 4;

struct Picked {
  std::size_t index;
  double horizontal;  // its range across the LiDAR's axis
  bool far_below_horizon;
};

}  // namespace

void update_beam_calibration(BeamCalibration& calibration, const DeskewedFeatures& features, const NavState& state,
                             const Pose& lidar_to_imu, const LocalMap& plane_map,
                             const CorrespondenceParams& correspondence, double lidar_noise_m) {
  const Eigen::Matrix3d world_from_lidar = state.rotation * lidar_to_imu.rotation.toRotationMatrix();
  const Eigen::Vector3d up = -state.gravity.normalized();
  const double max_elevation_slope = std::tan(kBeamMaxElevationRad);
  const bool learn_ranges = calibration.learns_ranges();
  // The candidates (the far ground below the horizon, or every plane point when ranges are
  // learned), every kBeamPointStride-th of each beam.
  std::vector<Picked> picked;
  std::vector<Eigen::Vector3d> world;
  std::vector<std::uint32_t> seen(calibration.beams(), 0);
  for (std::size_t i = 0; i < features.map_planes.size(); ++i) {
    const RingPoint& source = features.map_plane_sources[i];
    const double horizontal = std::hypot(source.lidar.x(), source.lidar.y());
    const bool far_below_horizon = horizontal >= kBeamMinRangeM && source.lidar.z() <= horizontal * max_elevation_slope;
    if (!far_below_horizon && !learn_ranges) continue;
    if (source.ring >= seen.size() || seen[source.ring]++ % kBeamPointStride != 0) continue;  // add_* would drop it
    picked.push_back({i, horizontal, far_below_horizon});
    world.push_back(state.to_world(features.map_planes[i]));
  }
  // Their planes searched voxel by voxel (as the registration's), added in sweep order.
  std::vector<std::optional<LinearResidual>> planes(picked.size());
  LocalMap::NeighbourSearch search(plane_map);
  for (const std::uint32_t k : plane_map.voxel_order(world)) planes[k] = plane_correspondence(search, world[k], correspondence);
  for (std::size_t k = 0; k < picked.size(); ++k) {
    const auto& plane = planes[k];
    if (!plane) continue;
    const double residual = plane->evaluate(world[k]);
    if (std::abs(residual) > kBeamResidualGateM) continue;
    const RingPoint& source = features.map_plane_sources[picked[k].index];
    const double variance = lidar_noise_m * lidar_noise_m * plane->variance_scale;
    if (picked[k].far_below_horizon && std::abs(plane->normal.dot(up)) >= kGroundNormalCos) {
      const double elevation = std::atan2(source.lidar.z(), picked[k].horizontal);
      const double jacobian = plane->normal.dot(world_from_lidar * BeamCalibration::elevation_derivative(source.lidar));
      calibration.add_elevation(source.ring, elevation, jacobian, residual, variance);
    } else {
      calibration.add_range(source.ring, plane->normal.dot(world_from_lidar * source.lidar.normalized()), residual,
                            variance);
    }
  }
  calibration.finish_scan();
}

}  // namespace liod
