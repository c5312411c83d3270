#include "liod/deskew.hpp"

#include <algorithm>

#include "liod/so3.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {

PoseTable deskew_trajectory(DeskewMode mode, double t_start, double t_end, const NavState& start, const NavState& end,
                            const std::vector<ImuInterval>& intervals, const Eigen::Vector3d& angular_rate) {
  PoseTable table;
  switch (mode) {
    case DeskewMode::kImu: {
      table = integrate_imu_poses(start, intervals, start.gravity);
      table.make_relative_to({Eigen::Quaterniond(end.rotation), end.position});
      break;
    }
    case DeskewMode::kConstantVelocity: {
      const Eigen::Vector3d v_body = end.rotation.transpose() * end.velocity;
      constexpr int kSteps = 10;
      for (int k = 0; k <= kSteps; ++k) {
        const double t = t_start + (t_end - t_start) * k / kSteps;
        const double before_end = t_end - t;
        table.add(t, {Eigen::Quaterniond(so3::exp(-angular_rate * before_end)), -v_body * before_end});
      }
      break;
    }
    case DeskewMode::kNone:
      table.add(t_end, {});
      break;
  }
  return table;
}

DeskewedFeatures deskew_features(const Scan& scan, const ScanFeatures& indices, const PoseTable& relative, double t0,
                                 const Pose& lidar_to_imu, const BeamCalibration& beams, const DeskewParams& params,
                                 bool flattest_queries) {
  DeskewedFeatures out;
  const double inverse_map_spacing = 1.0 / std::max(params.map_min_point_spacing_m, 0.05);
  // Thin the candidates on their raw coordinates first, so that only the survivors pay for the
  // per-point pose (a voxel shifts by less than the motion blur, which is all that changes).
  VoxelSet occupied(indices.planes.size());
  std::vector<Eigen::Vector3d> planes;
  planes.reserve(indices.planes.size() / 2);
  std::vector<float> plane_curvatures;
  plane_curvatures.reserve(indices.planes.size() / 2);
  auto lidar_point = [&](const LidarPoint& p) { return beams.correct(Eigen::Vector3d(p.x, p.y, p.z), p.ring); };
  auto deskewed = [&](const LidarPoint& p, const Eigen::Vector3d& in_lidar) {
    return relative.at(t0 + static_cast<double>(p.time)) * (lidar_to_imu * in_lidar);
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
  // The extractor lists a voxel's candidates sharpest first, and a ring crossing an edge or bent
  // by its range noise scores highest: the flattest is the better query (docs/design.md, "The
  // flattest plane query per voxel").
  if (flattest_queries) {
    out.planes = voxel_downsample_lowest(planes, plane_curvatures, params.plane_voxel_m);
  } else {
    out.planes = voxel_downsample(planes, params.plane_voxel_m);
  }
  out.edges = voxel_downsample(edges, params.edge_voxel_m);
  return out;
}

}  // namespace liod
