// Registration on real RS-Helios-5515 scans (shared/data/robosense/helios32_decoded): pairs of
// scans 0.1 s apart, recorded on a vehicle in a close, enclosed place, must register with a
// small plausible motion and a residual at the sensor's noise level.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "liod/curvature_features.hpp"
#include "liod/drivers/pcd_io.hpp"
#include "liod/iterated_update.hpp"
#include "liod/so3.hpp"
#include "liod/voxel_grid.hpp"
#include "test_env.hpp"

namespace {

namespace fs = std::filesystem;
const fs::path kDir = fs::path(LIOD_SHARED_DIR) / "data/robosense/helios32_decoded";

// nebula's clouds carry the ring (`channel`, 0 = lowest beam) and the azimuth in 0.01 deg, but
// only the packet second as time: the point time is recovered from the azimuth at 10 Hz.
liod::Scan load_scan(const fs::path& path) {
  const auto cloud = liod::drivers::read_pcd(path);
  const int x = cloud.field_index("x");
  const int y = cloud.field_index("y");
  const int z = cloud.field_index("z");
  const int ch = cloud.field_index("channel");
  const int az = cloud.field_index("azimuth");
  if (x < 0 || y < 0 || z < 0 || ch < 0 || az < 0) throw std::runtime_error("missing fields in " + path.string());
  double min_az = 1e9;
  for (std::size_t i = 0; i < cloud.points(); ++i) min_az = std::min(min_az, cloud.value(i, static_cast<std::size_t>(az)));
  liod::Scan scan;
  scan.beam_count = 32;
  for (std::size_t i = 0; i < cloud.points(); ++i) {
    liod::LidarPoint p;
    p.x = static_cast<float>(cloud.value(i, static_cast<std::size_t>(x)));
    p.y = static_cast<float>(cloud.value(i, static_cast<std::size_t>(y)));
    p.z = static_cast<float>(cloud.value(i, static_cast<std::size_t>(z)));
    p.ring = static_cast<std::uint16_t>(cloud.value(i, static_cast<std::size_t>(ch)));
    p.time = static_cast<float>((cloud.value(i, static_cast<std::size_t>(az)) - min_az) / 36000.0 * 0.1);
    scan.points.push_back(p);
  }
  return scan;
}

struct BodyFeatures {
  std::vector<Eigen::Vector3d> planes;
  std::vector<Eigen::Vector3d> edges;
};

BodyFeatures features_of(const liod::Scan& scan, const liod::FeatureParams& params) {
  liod::FeatureExtractor extractor(params);
  liod::ScanFeatures f;
  extractor.extract(scan, f);
  BodyFeatures out;
  for (auto i : f.planes) out.planes.emplace_back(scan.points[i].x, scan.points[i].y, scan.points[i].z);
  for (auto i : f.edges) out.edges.emplace_back(scan.points[i].x, scan.points[i].y, scan.points[i].z);
  out.planes = liod::voxel_downsample(out.planes, 0.1);
  return out;
}

TEST(RealHelios32, ConsecutiveScansRegisterWithSmallMotion) {
  LIOD_REQUIRE_SHARED(kDir);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kDir)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 8U);

  liod::FeatureParams params;
  // The scene is close: the vehicle itself is within ~1 m and the walls within a few metres.
  params.min_range_m = 1.0;
  params.max_range_m = 60.0;
  int pairs = 0;
  for (std::size_t k = 0; k + 1 < files.size(); ++k) {
    const double t0 = std::stod(files[k].stem().string()) * 1e-9;
    const double t1 = std::stod(files[k + 1].stem().string()) * 1e-9;
    if (t1 - t0 > 0.15) continue;  // only scans 0.1 s apart
    ++pairs;
    const auto reference = features_of(load_scan(files[k]), params);
    const auto current = features_of(load_scan(files[k + 1]), params);
    liod::LocalMap map(0.5, 30, 0.05);
    liod::LocalMap edge_map(0.5, 30, 0.05);
    map.add(reference.planes, 0);
    edge_map.add(reference.edges, 0);
    ASSERT_GT(current.planes.size(), 300U);

    // A LiDAR-only registration: a weak prior at zero motion (1 m, 10 deg standard deviations).
    liod::StateCovariance prior = liod::StateCovariance::Identity() * 1e-6;
    prior.block<3, 3>(0, 0) = Eigen::Matrix3d::Identity() * 0.03;
    prior.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * 1.0;
    liod::UpdateParams update;
    update.max_iterations = 15;
    update.lidar_noise_m = 0.02;
    update.correspondence.max_distance_m = 0.5;
    update.correspondence.max_plane_thickness_m = 0.05;
    const auto result = liod::iterated_update(liod::NavState{}, prior, current.planes, map, current.edges, edge_map, update);
    const double translation = result.state.position.norm();
    const double rotation_deg = liod::so3::log(result.state.rotation).norm() * 180.0 / M_PI;
    std::printf("pair %s -> %s: motion %.3f m (%.3f, %.3f, %.3f), %.2f deg, %d residuals, rms %.4f m\n",
                files[k].stem().c_str(), files[k + 1].stem().c_str(), translation, result.state.position.x(),
                result.state.position.y(), result.state.position.z(), rotation_deg, result.residuals,
                result.rms_residual_m);
    EXPECT_LT(translation, 1.0);     // <= 10 m/s in 0.1 s, in a close, enclosed place
    EXPECT_LT(rotation_deg, 3.0);
    EXPECT_GT(result.residuals, 300);
    EXPECT_LT(result.rms_residual_m, 0.03);  // the sensor's ~2 cm noise level

    // The recording barely moves, so also start 0.25 m and 3 deg away: it must come back.
    liod::NavState offset;
    offset.position = Eigen::Vector3d(0.2, -0.1, 0.1);
    offset.rotation = liod::so3::exp(Eigen::Vector3d(0.0, 0.01, 0.05));
    const auto again = liod::iterated_update(offset, prior, current.planes, map, current.edges, edge_map, update);
    EXPECT_LT((again.state.position - result.state.position).norm(), 0.02);
    EXPECT_LT(liod::so3::log(again.state.rotation.transpose() * result.state.rotation).norm() * 180.0 / M_PI, 0.2);
  }
  EXPECT_EQ(pairs, 5);
}

}  // namespace
