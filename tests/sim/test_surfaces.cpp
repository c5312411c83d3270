// Decoded points lie on the simulated surfaces: each point, mapped to the world with the ground-
// truth pose and extrinsic at its own firing time, is checked against the world's geometry.
// Decoded twice: by the test's own spec reader and by liod's RS-Helios decoder (liod_drivers).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "helios_reader.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "sim_test_util.hpp"

namespace liod::sim::test {
namespace {

struct Residuals {
  std::vector<double> world;
  std::size_t ego = 0;
  double ego_worst = 0.0;
};

double ego_distance(const EgoBody& e, const Eigen::Vector3d& p) {
  double best = 1e9;
  for (std::size_t i = 0; i < e.box_min.size(); ++i) {
    const Eigen::Vector3d c = 0.5 * (e.box_min[i] + e.box_max[i]);
    const Eigen::Vector3d h = 0.5 * (e.box_max[i] - e.box_min[i]);
    const Eigen::Vector3d q = (p - c).cwiseAbs() - h;
    best = std::min(best, std::abs(q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0)));
  }
  return best;
}

/// Maps a LiDAR-frame point measured at LiDAR-clock time t_abs to the world and measures it.
void add_point(const Simulation& sim, const Eigen::Vector3d& pl, double t_abs, Residuals& r) {
  const double t_imu = t_abs - static_cast<double>(sim.config().epoch_s) + sim.time_offset();
  const Eigen::Vector3d pb = sim.imu_from_lidar().rotation * pl + sim.imu_from_lidar().translation;
  const double de = ego_distance(sim.ego(), pb);
  if (de < 0.3) {
    ++r.ego;
    r.ego_worst = std::max(r.ego_worst, de);
    return;
  }
  const Pose T = sim.trajectory().pose(t_imu);
  r.world.push_back(sim.scene().world.distance_to_world(T.rotation * pb + T.translation));
}

double quantile(std::vector<double> v, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

Simulation make_run(bool noise, const std::string& dir) {
  SimConfig c = short_config(RouteKind::Urban, 21, 3.0, dir);
  c.noise = noise;
  c.scene.max_speed = 15.0;
  Simulation sim(c);
  sim.write_all();
  return sim;
}

Residuals decode_with_spec_reader(const Simulation& sim, const std::string& dir) {
  std::array<double, 32> vert{};
  std::array<double, 32> horiz{};
  const HeliosCalibration& cal = sim.lidar().published();
  std::copy(cal.vertical_deg.begin(), cal.vertical_deg.end(), vert.begin());
  std::copy(cal.horizontal_deg.begin(), cal.horizontal_deg.end(), horiz.begin());
  Residuals r;
  std::vector<DecodedPoint> pts;
  std::size_t k = 0;
  for (const auto& rec : read_pcap(dir + "/lidar.pcap")) {
    if (rec.dst_port != 6699 || (k++ % 3) != 0) {
      continue;
    }
    pts.clear();
    decode_msop(rec.payload, vert, horiz, pts);
    for (const auto& p : pts) {
      add_point(sim, Eigen::Vector3d(p.x, p.y, p.z), p.time_s, r);
    }
  }
  return r;
}

void expect_on_surfaces(const Residuals& r, double median_max, double p95_max, const char* what) {
  ASSERT_GT(r.world.size(), 50000U) << what;
  EXPECT_GT(r.ego, 1000U) << what << ": the LiDAR should see its own car";
  EXPECT_LT(r.ego_worst, 0.1) << what;
  const double med = quantile(r.world, 0.5);
  const double p95 = quantile(r.world, 0.95);
  std::printf("%s: %zu points, median %.4f m, p95 %.4f m, p99 %.4f m (%zu ego points)\n", what,
              r.world.size(), med, p95, quantile(r.world, 0.99), r.ego);
  EXPECT_LT(med, median_max) << what;
  EXPECT_LT(p95, p95_max) << what;
}

TEST(SimSurfaces, SpecDecodedPointsLieOnSurfacesWithinNoise) {
  LIOD_SIM_REQUIRE_SHARED();
  const std::string dir = scratch_dir("surf-noisy");
  const Simulation sim = make_run(true, dir);
  expect_on_surfaces(decode_with_spec_reader(sim, dir), 0.03, 0.08, "spec reader, noisy");
}

TEST(SimSurfaces, NoiseFreeGeometryIsExact) {
  LIOD_SIM_REQUIRE_SHARED();
  // Without range noise only quantisation (1.25 mm) and time-stamp truncation remain: any error
  // in firing times, azimuth interpolation, lens offset or mounting would show up here.
  const std::string dir = scratch_dir("surf-exact");
  const Simulation sim = make_run(false, dir);
  expect_on_surfaces(decode_with_spec_reader(sim, dir), 0.003, 0.01, "spec reader, noise-free");
}

TEST(SimSurfaces, LiodDecoderPointsLieOnSurfaces) {
  LIOD_SIM_REQUIRE_SHARED();
  const std::string dir = scratch_dir("surf-liod");
  const Simulation sim = make_run(true, dir);
  drivers::HeliosOptions opt;
  opt.angles = drivers::load_angles_csv(angles_csv());
  Residuals r;
  std::size_t scans = 0;
  drivers::RsHeliosDecoder dec(opt, [&](Scan& scan, const drivers::SweepInfo&) {
    ++scans;
    for (std::size_t i = 0; i < scan.points.size(); i += 3) {
      const auto& p = scan.points[i];
      add_point(sim, Eigen::Vector3d(p.x, p.y, p.z),
                scan.start_time + static_cast<double>(p.time), r);
    }
  });
  drivers::PcapReader reader(dir + "/lidar.pcap");
  drivers::UdpDatagram d;
  while (reader.next(d)) {
    dec.feed(d.payload, d.capture_time_ns);
  }
  dec.flush();
  EXPECT_GE(scans, 28U);
  EXPECT_EQ(dec.stats().rejected(), 0U);
  EXPECT_EQ(dec.stats().lost_packets, 0U);
  expect_on_surfaces(r, 0.03, 0.08, "liod decoder, noisy");
}

// The unit's true angles stray from its published table by at most the configured error, each
// channel by its own amount, and only the angles change: the range biases stay the same draws.
TEST(SimSurfaces, AngleErrorBoundsTheTrueAnglesAndLeavesTheRangeBiases) {
  const std::string dir = scratch_dir("angle_error");
  std::array<double, kChannels> biases{};
  for (const double error : {0.0, 0.005, 0.02}) {
    SimConfig c = short_config(RouteKind::Urban, 21, 1.0, dir);
    c.angle_error_deg = error;
    const Simulation sim(c);
    const HeliosCalibration& published = sim.lidar().published();
    const HeliosCalibration& truth = sim.lidar().true_angles();
    double largest = 0.0;
    for (int k = 0; k < kChannels; ++k) {
      const auto i = static_cast<std::size_t>(k);
      largest = std::max({largest, std::abs(truth.vertical_deg[i] - published.vertical_deg[i]),
                          std::abs(truth.horizontal_deg[i] - published.horizontal_deg[i])});
    }
    EXPECT_LE(largest, error) << "angle error " << error;
    EXPECT_GE(largest, 0.5 * error) << "angle error " << error;  // 64 uniform draws all below half: 5e-20
    if (error == 0.0) {
      biases = sim.lidar().channel_bias();
    } else {
      EXPECT_EQ(sim.lidar().channel_bias(), biases) << "angle error " << error;
    }
  }
}

// Each channel's ranges carry its own calibration bias (the scenario's channel_bias_m) on top of the
// noise: averaged over many returns off a wall 10 m away, a channel reads 10 m plus its bias.
TEST(SimSurfaces, EachChannelsRangesCarryItsBias) {
  const std::string dir = scratch_dir("channel_bias");
  const Simulation sim(short_config(RouteKind::Urban, 21, 1.0, dir));
  const auto& biases = sim.lidar().channel_bias();
  RayHit wall;
  wall.range = 10.0;
  wall.cos_incidence = 1.0;
  wall.reflectivity = 0.5F;
  Rng rng(7);
  constexpr int kDraws = 4000;  // the mean's error: ~0.02 m / sqrt(4000) = 0.3 mm
  double largest_bias = 0.0;
  for (int c = 0; c < kChannels; ++c) {
    double sum = 0.0;
    int n = 0;
    for (int k = 0; k < kDraws; ++k) {
      ChannelReturn out{};
      double strength = 0.0;
      if (!sim.lidar().measure(wall, false, c, rng, out, &strength)) continue;
      sum += out.raw * kRangeUnit;
      ++n;
    }
    ASSERT_GT(n, kDraws * 9 / 10) << "channel " << c;
    const auto i = static_cast<std::size_t>(c);
    EXPECT_NEAR(sum / n - 10.0, biases[i], 0.0015) << "channel " << c;
    largest_bias = std::max(largest_bias, std::abs(biases[i]));
  }
  EXPECT_GT(largest_bias, 0.005);  // 32 draws of sigma 4 mm: the check above sees the biases
}

}  // namespace
}  // namespace liod::sim::test
