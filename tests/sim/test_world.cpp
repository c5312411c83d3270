// Building blocks: random streams, ray casting against the distance query, trajectory
// derivatives against finite differences, CLI validation.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "liod/sim/rng.hpp"
#include "sim_test_util.hpp"

namespace liod::sim::test {
namespace {

TEST(SimRng, GaussianHasUnitVarianceAndIsReproducible) {
  Rng a(5);
  Rng b(5);
  double s = 0.0;
  double s2 = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = a.gaussian();
    ASSERT_EQ(x, b.gaussian());
    s += x;
    s2 += x * x;
  }
  EXPECT_NEAR(s / n, 0.0, 0.01);
  EXPECT_NEAR(s2 / n, 1.0, 0.01);
  EXPECT_NE(derive_seed(1, 2, 3), derive_seed(1, 2, 4));
}

TEST(SimWorld, RayHitsLieOnTheSurfacesTheDistanceQueryKnows) {
  LIOD_SIM_REQUIRE_SHARED();
  const Simulation sim(short_config(RouteKind::Urban, 4, 20.0, ""));
  const World& w = sim.scene().world;
  RayContext ctx(w, 1);
  Rng rng(2);
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const BodyState s = sim.trajectory().state(rng.uniform(0.0, 20.0));
    const Eigen::Vector3d o = s.position + Eigen::Vector3d(0, 0, 1.0);
    const double az = rng.uniform(0.0, 2.0 * M_PI);
    const double el = rng.uniform(-0.5, 0.3);
    const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    RayHit h;
    if (w.cast(o, d, 150.0, ctx, h)) {
      ++hits;
      ASSERT_LT(w.distance_to_world(o + h.range * d), 2e-3) << "ray " << i << " range " << h.range;
      ASSERT_GE(h.cos_incidence, 0.0);
      ASSERT_LE(h.cos_incidence, 1.0 + 1e-9);
    }
  }
  EXPECT_GT(hits, 15000);
}

TEST(SimTrajectory, AnalyticDerivativesMatchFiniteDifferences) {
  LIOD_SIM_REQUIRE_SHARED();
  const Simulation sim(short_config(RouteKind::Urban, 6, 30.0, ""));
  const Trajectory& tr = sim.trajectory();
  const double h = 1e-5;
  for (double t = 0.3; t < 29.0; t += 0.77) {
    const BodyState s = tr.state(t);
    const BodyState a = tr.state(t - h);
    const BodyState b = tr.state(t + h);
    EXPECT_LT(((b.position - a.position) / (2 * h) - s.velocity).norm(), 1e-4) << t;
    EXPECT_LT(((b.velocity - a.velocity) / (2 * h) - s.acceleration).norm(), 2e-3) << t;
    // R^T dR/dt = [w]x in the body frame.
    const Eigen::Matrix3d W = s.rotation.transpose() * (b.rotation - a.rotation) / (2 * h);
    const Eigen::Vector3d w(W(2, 1), W(0, 2), W(1, 0));
    EXPECT_LT((w - s.angular_velocity).norm(), 1e-5) << t;
    EXPECT_LT(s.velocity.norm(), 12.0 + 0.3);
  }
}

TEST(SimTrajectory, VehicleStaysOnTheRoadAndTheGround) {
  LIOD_SIM_REQUIRE_SHARED();
  const Simulation sim(short_config(RouteKind::Urban, 9, 60.0, ""));
  const World& w = sim.scene().world;
  double zmin = 1e9;
  double zmax = -1e9;
  for (double t = 0.0; t < 60.0; t += 0.1) {
    const BodyState s = sim.trajectory().state(t);
    const double above = s.position.z() - w.ground_height(s.position.x(), s.position.y());
    EXPECT_NEAR(above, 0.80, 0.05) << t;
    EXPECT_EQ(w.ground_type_at(s.position.x(), s.position.y()), GroundType::Asphalt) << t;
    zmin = std::min(zmin, s.position.z());
    zmax = std::max(zmax, s.position.z());
  }
  EXPECT_GT(zmax - zmin, 0.5) << "the drive should climb or descend";
}

int run_cli(const std::string& args) {
  const std::string bin = std::string(LIOD_BINARY_DIR) + "/bin/liod-sim";
  const int rc = std::system((bin + " " + args + " > /dev/null 2>&1").c_str());
  return rc;
}

TEST(SimCli, RejectsBadInputWithNonZeroExit) {
  LIOD_SIM_REQUIRE_SHARED();
  LIOD_REQUIRE_PROGRAM("liod-sim");
  const std::string dir = scratch_dir("cli");
  EXPECT_NE(run_cli("--route mars --seed 1 --duration 1 --out " + dir), 0);
  EXPECT_NE(run_cli("--route urban --seed 1 --duration -1 --out " + dir), 0);
  EXPECT_NE(run_cli("--route urban --seed 1 --duration 1 --out " + dir + "/missing"), 0);
  EXPECT_NE(run_cli("--route urban --seed 1 --duration 1 --out " + dir + " --angles /nonexistent.csv"), 0);
  EXPECT_NE(run_cli("--route urban --seed 1 --duration 1"), 0);
  EXPECT_EQ(run_cli("--route tunnel --seed 1 --duration 1 --max-speed 15 --quiet --out " + dir), 0);
  EXPECT_TRUE(std::filesystem::exists(dir + "/lidar.pcap"));
}

}  // namespace
}  // namespace liod::sim::test
