// The noise-free IMU log, integrated from the true initial state, reproduces the ground truth:
// the IMU, the trajectory and the ground-truth file describe the same motion.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "liod/sim/imu_model.hpp"
#include "sim_test_util.hpp"

namespace liod::sim::test {
namespace {

struct Nav {
  Eigen::Quaterniond q;
  Eigen::Vector3d v;
  Eigen::Vector3d p;
};

struct Deriv {
  Eigen::Vector4d dq;
  Eigen::Vector3d dv;
  Eigen::Vector3d dp;
};

Deriv derivative(const Nav& s, const Eigen::Vector3d& w, const Eigen::Vector3d& f) {
  const Eigen::Quaterniond wq(0.0, w.x(), w.y(), w.z());
  const Eigen::Quaterniond qd = s.q * wq;
  Deriv d;
  d.dq = 0.5 * qd.coeffs();
  d.dv = s.q.toRotationMatrix() * f + Eigen::Vector3d(0.0, 0.0, -kGravity);
  d.dp = s.v;
  return d;
}

Nav advance(const Nav& s, const Deriv& d, double h) {
  Nav n;
  n.q.coeffs() = s.q.coeffs() + h * d.dq;
  n.q.normalize();
  n.v = s.v + h * d.dv;
  n.p = s.p + h * d.dp;
  return n;
}

void check_integration(RouteKind route, std::uint64_t seed, const std::string& name) {
  const std::string dir = scratch_dir(name);
  SimConfig c = short_config(route, seed, 10.5, dir);
  c.noise = false;
  c.scene.max_speed = 15.0;
  const Simulation sim(c);
  sim.write_all();
  const auto imu = read_numbers(dir + "/imu.csv", ',', true);
  const auto gt = read_numbers(dir + "/groundtruth.tum", ' ', false);
  ASSERT_EQ(imu.size(), gt.size());
  ASSERT_EQ(imu.size(), 2101U);

  const BodyState s0 = sim.trajectory().state(0.0);
  Nav nav{Eigen::Quaterniond(gt[0][7], gt[0][4], gt[0][5], gt[0][6]), s0.velocity,
          Eigen::Vector3d(gt[0][1], gt[0][2], gt[0][3])};
  auto w_of = [&](std::size_t k) { return Eigen::Vector3d(imu[k][1], imu[k][2], imu[k][3]); };
  auto f_of = [&](std::size_t k) { return Eigen::Vector3d(imu[k][4], imu[k][5], imu[k][6]); };
  const std::size_t steps = 2000;  // 10 s at 200 Hz
  for (std::size_t k = 0; k < steps; ++k) {
    const double h = imu[k + 1][0] - imu[k][0];
    ASSERT_NEAR(h, 0.005, 1e-6);
    const Eigen::Vector3d w0 = w_of(k);
    const Eigen::Vector3d w1 = w_of(k + 1);
    const Eigen::Vector3d f0 = f_of(k);
    const Eigen::Vector3d f1 = f_of(k + 1);
    const Eigen::Vector3d wm = 0.5 * (w0 + w1);
    const Eigen::Vector3d fm = 0.5 * (f0 + f1);
    const Deriv k1 = derivative(nav, w0, f0);
    const Deriv k2 = derivative(advance(nav, k1, h / 2), wm, fm);
    const Deriv k3 = derivative(advance(nav, k2, h / 2), wm, fm);
    const Deriv k4 = derivative(advance(nav, k3, h), w1, f1);
    Deriv sum;
    sum.dq = (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq) / 6.0;
    sum.dv = (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv) / 6.0;
    sum.dp = (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp) / 6.0;
    nav = advance(nav, sum, h);
  }
  const auto& g = gt[steps];
  const Eigen::Vector3d p_true(g[1], g[2], g[3]);
  const Eigen::Quaterniond q_true(g[7], g[4], g[5], g[6]);
  const double pos_err = (nav.p - p_true).norm();
  const double att_err_deg = q_true.angularDistance(nav.q) * 180.0 / M_PI;
  const double travelled = (p_true - Eigen::Vector3d(gt[0][1], gt[0][2], gt[0][3])).norm();
  EXPECT_GT(travelled, 40.0) << "the vehicle should move during the test";
  EXPECT_LT(pos_err, 0.05) << route_name(route);
  EXPECT_LT(att_err_deg, 0.1) << route_name(route);
  ::testing::Test::RecordProperty(std::string(route_name(route)) + "_pos_err_m", std::to_string(pos_err));
  std::printf("%s: 10 s integration error %.4f m, %.5f deg over %.0f m\n", route_name(route),
              pos_err, att_err_deg, travelled);
}

TEST(SimImu, NoiseFreeImuIntegratesToGroundTruthUrban) {
  LIOD_SIM_REQUIRE_SHARED();
  check_integration(RouteKind::Urban, 11, "imu-urban");
}

TEST(SimImu, NoiseFreeImuIntegratesToGroundTruthHighway) {
  LIOD_SIM_REQUIRE_SHARED();
  check_integration(RouteKind::Highway, 12, "imu-highway");
}

TEST(SimImu, AtRestTheAccelerometerReadsGravity) {
  LIOD_SIM_REQUIRE_SHARED();
  SimConfig c = short_config(RouteKind::Loop, 5, 5.0, "");
  c.scene.start = StartMode::Static;
  const Simulation sim(c);
  // Average over whole vibration periods: at rest only engine vibration moves the body.
  Eigen::Vector3d mean_f = Eigen::Vector3d::Zero();
  double max_speed = 0.0;
  const int n = 400;
  for (int i = 0; i < n; ++i) {
    const BodyState s = sim.trajectory().state(0.5 + 2.0 * i / n);
    max_speed = std::max(max_speed, s.velocity.norm());
    mean_f += ideal_imu(s).accel / n;
  }
  EXPECT_LT(max_speed, 5e-3);
  EXPECT_NEAR(mean_f.norm(), kGravity, 0.01);
  // Level within the road grade: z carries most of gravity.
  EXPECT_GT(mean_f.z(), kGravity * std::cos(0.12));
}

TEST(SimImu, NoisyImuHasTheStatedBiasesAndNoise) {
  LIOD_SIM_REQUIRE_SHARED();
  ImuNoise n;
  ImuModel m(n, 200.0, 99);
  BodyState rest;
  Eigen::Vector3d sum_g = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_g2 = Eigen::Vector3d::Zero();
  const int N = 2000;
  for (int i = 0; i < N; ++i) {
    const ImuReading r = m.measure(rest);
    sum_g += r.gyro;
    sum_g2 += r.gyro.cwiseProduct(r.gyro);
  }
  const Eigen::Vector3d mean = sum_g / N;
  const Eigen::Vector3d var = sum_g2 / N - mean.cwiseProduct(mean);
  for (int i = 0; i < 3; ++i) {
    EXPECT_GT(std::abs(mean[i]), 0.08 * M_PI / 180.0);  // turn-on bias 0.1..0.3 deg/s
    EXPECT_LT(std::abs(mean[i]), 0.32 * M_PI / 180.0);
    EXPECT_NEAR(std::sqrt(var[i]), n.gyro_noise_density * std::sqrt(200.0), 2e-4);
  }
}

}  // namespace
}  // namespace liod::sim::test
