// The publishing path's state gate: whatever the filter's state becomes, a pose goes out `ok`
// only with a finite, plausible state (docs/pose-protocol.md, flag `implausible`), and IMU-rate
// poses are never `ok` when the scan pose they are propagated from was not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

#include "liod/daemon/state_gate.hpp"
#include "pipeline_run.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"

using namespace liod;
using namespace liod::test;

namespace {

bool finite_message(const pose::PoseMessage& m) {
  return std::isfinite(m.time) && m.position.allFinite() && m.orientation.coeffs().allFinite() && m.velocity.allFinite() &&
         m.angular_rate.allFinite() && m.covariance.allFinite();
}

/// The drive with one IMU sample, `at_s` after the log's first, turned into `accel_x` m/s^2 (a
/// serial frame that passed its checksum with garbage in it). The IMU's measurement range is set
/// wider than any value, as for a unit whose range the configuration does not state: the range
/// check that would drop the sample is then off, and the state gate is the last line.
PipelineRun run_with_accel_spike(const std::filesystem::path& drive, double at_s, const std::string& accel_x) {
  const ScratchDir dir("spike");
  double first = -1.0;
  bool done = false;
  rewrite_imu_log(drive / "imu.csv", dir / "imu.csv", [&](double t, const std::string& line) {
    if (first < 0.0) first = t;
    if (done || t < first + at_s) return line;
    done = true;
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string x; std::getline(s, x, ',');) f.push_back(x);
    f[4] = accel_x;
    return f[0] + ',' + f[1] + ',' + f[2] + ',' + f[3] + ',' + f[4] + ',' + f[5] + ',' + f[6];
  });
  Config config = drive_config(drive);
  config.imu.accel_range_m_s2 = std::numeric_limits<double>::infinity();
  return run_pipeline(config, drive / "lidar.pcap", dir / "imu.csv", 0.0);
}

struct GateFindings {
  std::size_t ok = 0, ok_non_finite = 0, ok_too_fast = 0, imu_ok_after_bad_scan = 0, not_ok_scans = 0;
  double fastest_ok_mps = 0.0;
};

GateFindings examine(const PipelineRun& run) {
  GateFindings g;
  bool last_scan_ok = true;  // in publish order (lockstep: an IMU-rate pose follows its scan pose)
  for (const auto& p : run.poses) {
    const auto& m = p.event.message;
    const bool ok = (m.flags & pose::kOk) != 0;
    if (m.type == pose::MessageType::ScanPose) {
      last_scan_ok = ok;
      if (!ok) ++g.not_ok_scans;
    } else if (ok && !last_scan_ok) {
      ++g.imu_ok_after_bad_scan;
    }
    if (!ok) continue;
    ++g.ok;
    if (!finite_message(m)) {
      ++g.ok_non_finite;
      continue;
    }
    g.fastest_ok_mps = std::max(g.fastest_ok_mps, m.velocity.norm());
    if (m.velocity.norm() > 100.0) ++g.ok_too_fast;
  }
  return g;
}

void expect_gate_held(const GateFindings& g, const char* what) {
  std::printf("[ gate ] %s: %zu ok poses, %zu ok but not finite, %zu ok faster than 100 m/s (fastest %.3g m/s), "
              "%zu not-ok scan poses, %zu ok IMU-rate poses after a not-ok scan pose\n",
              what, g.ok, g.ok_non_finite, g.ok_too_fast, g.fastest_ok_mps, g.not_ok_scans, g.imu_ok_after_bad_scan);
  EXPECT_GT(g.ok, 0U) << "the poses before the fault are ok";
  EXPECT_EQ(g.ok_non_finite, 0U);
  EXPECT_EQ(g.ok_too_fast, 0U);
  EXPECT_EQ(g.imu_ok_after_bad_scan, 0U);
}

}  // namespace

// 1e5 m/s^2 for one 5 ms sample: 500 m/s of velocity out of nothing.
TEST(PublishGate, AbsurdAccelerationIsNeverPublishedOk) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const PipelineRun run = run_with_accel_spike(*drive, 4.0, "100000");
  ASSERT_EQ(run.error, "");
  expect_gate_held(examine(run), "accel 1e5 m/s^2 at 4 s");
}

// 1e300 m/s^2: finite on the wire, but the state overflows to inf and NaN.
TEST(PublishGate, OverflowingStateIsNeverPublishedOk) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const PipelineRun run = run_with_accel_spike(*drive, 4.0, "1e300");
  ASSERT_EQ(run.error, "");
  expect_gate_held(examine(run), "accel 1e300 m/s^2 at 4 s");
}

// The gate on the clean drive: nothing to withhold.
TEST(PublishGate, CleanDriveIsNeverImplausible) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const PipelineRun run = run_pipeline(drive_config(*drive), *drive / "lidar.pcap", *drive / "imu.csv", 0.0);
  ASSERT_EQ(run.error, "");
  std::size_t implausible = 0, ok_scans = 0;
  for (const auto& p : run.poses) {
    if (p.event.message.flags & pose::kImplausible) ++implausible;
    if (p.event.message.type == pose::MessageType::ScanPose && (p.event.message.flags & pose::kOk)) ++ok_scans;
  }
  EXPECT_EQ(implausible, 0U);
  EXPECT_GT(ok_scans, 60U);
  EXPECT_NE(run.health.find("\"implausible_poses\":0"), std::string::npos) << run.health;
}

// The odometry does not carry an implausible state on: it starts up again (speed search) at the
// last plausible pose (reinitialization.hpp), and its poses are ok again.
// The new start is where the last plausible pose was, carried on by the gyro: the vehicle moved on
// while the start-up found its speed (0.9 m here); from there the odometry tracks the motion as the
// clean replay does (within 0.04 m over 3.5 s).
TEST(PublishGate, ImplausibleStateRestartsTheOdometry) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto ref = read_tum(reference_replay(*drive) / "scan.tum");
  ASSERT_GT(ref.size(), 50U);
  const double spike_t = ref.front().t + 4.0;
  const PipelineRun run = run_with_accel_spike(*drive, 4.0, "100000");
  ASSERT_EQ(run.error, "");
  EXPECT_EQ(run.health.find("\"restarts\":0"), std::string::npos) << run.health;
  std::size_t ok_after = 0;
  std::optional<Eigen::Vector3d> offset;  // of the first ok pose after the restart from the clean one
  double worst_m = 0.0;
  for (const auto& p : run.poses) {
    const auto& m = p.event.message;
    if (m.type != pose::MessageType::ScanPose || !(m.flags & pose::kOk) || m.time < spike_t) continue;
    for (const auto& r : ref) {
      if (std::abs(r.t - m.time) > 1e-6) continue;
      const Eigen::Vector3d d = m.position - Eigen::Vector3d(r.x, r.y, r.z);
      if (!offset) offset = d;
      worst_m = std::max(worst_m, (d - *offset).norm());
      ++ok_after;
    }
  }
  ASSERT_TRUE(offset.has_value()) << "no ok scan pose after the restart";
  std::printf("[ gate ] after the restart: %zu ok scan poses, the first %.3f m from the clean replay's, the others "
              "within %.3f m of that offset\n", ok_after, offset->norm(), worst_m);
  EXPECT_GE(ok_after, 20U);
  EXPECT_LT(offset->norm(), 2.0);
  EXPECT_LT(worst_m, 0.15);
}

TEST(PublishGate, FlaggedPosesAreCountedInHealth) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const PipelineRun run = run_with_accel_spike(*drive, 4.0, "100000");
  std::size_t implausible = 0;
  for (const auto& p : run.poses) implausible += (p.event.message.flags & pose::kImplausible) != 0;
  EXPECT_GT(implausible, 0U);
  EXPECT_NE(run.health.find("\"implausible_poses\":" + std::to_string(implausible) + ","), std::string::npos) << run.health;
}

namespace {

NavState plausible_state() {
  NavState s;
  s.time = 12.5;
  s.rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  s.position = {10, -4, 1};
  s.velocity = {25, 1, 0};
  s.gyro_bias = {0.002, -0.001, 0.003};
  s.accel_bias = {0.05, -0.1, 0.02};
  return s;
}

}  // namespace

TEST(StateGate, ChecksEachPartOfTheState) {
  const StateLimits limits;  // 100 m/s, 0.1 rad/s, 1 m/s^2
  EXPECT_EQ(check_state(plausible_state(), limits), StateFault::kNone);
  auto broken = [&](auto edit) {
    NavState s = plausible_state();
    edit(s);
    return check_state(s, limits);
  };
  EXPECT_EQ(broken([](NavState& s) { s.time = std::nan(""); }), StateFault::kNotFinite);
  EXPECT_EQ(broken([](NavState& s) { s.position.y() = INFINITY; }), StateFault::kNotFinite);
  EXPECT_EQ(broken([](NavState& s) { s.rotation(1, 2) = std::nan(""); }), StateFault::kNotFinite);
  EXPECT_EQ(broken([](NavState& s) { s.gravity.z() = -INFINITY; }), StateFault::kNotFinite);
  EXPECT_EQ(broken([](NavState& s) { s.rotation *= 1.01; }), StateFault::kRotation);
  EXPECT_EQ(broken([](NavState& s) { s.rotation.col(0) *= -1.0; }), StateFault::kRotation);  // a reflection
  EXPECT_EQ(broken([](NavState& s) { s.velocity = {99.0, 0, 0}; }), StateFault::kNone);
  EXPECT_EQ(broken([](NavState& s) { s.velocity = {80.0, 0, 70.0}; }), StateFault::kSpeed);
  EXPECT_EQ(broken([](NavState& s) { s.velocity = {1e300, 1e300, 0}; }), StateFault::kSpeed);  // norm overflows
  EXPECT_EQ(broken([](NavState& s) { s.gyro_bias.z() = -0.11; }), StateFault::kGyroBias);
  EXPECT_EQ(broken([](NavState& s) { s.accel_bias.x() = 1.2; }), StateFault::kAccelBias);
  StateLimits strict = limits;
  strict.max_speed_mps = 20.0;
  EXPECT_EQ(check_state(plausible_state(), strict), StateFault::kSpeed);
}

TEST(StateGate, CovarianceMustBePositiveDefinite) {
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(17, 17) * 1e-4;
  c(3, 4) = c(4, 3) = 5e-5;
  EXPECT_EQ(check_covariance(c), StateFault::kNone);
  Eigen::MatrixXd tiny = Eigen::MatrixXd::Identity(6, 6) * 1e-14;  // a converged bias: small, still definite
  EXPECT_EQ(check_covariance(tiny), StateFault::kNone);
  Eigen::MatrixXd m = c;
  m(5, 5) = -1e-6;
  EXPECT_EQ(check_covariance(m), StateFault::kCovariance);
  m = c;
  m(7, 7) = 0.0;  // semi-definite: a direction the filter claims to know exactly
  EXPECT_EQ(check_covariance(m), StateFault::kCovariance);
  m = c;
  m(3, 4) = 2e-4;  // |correlation| > 1
  m(4, 3) = 2e-4;
  EXPECT_EQ(check_covariance(m), StateFault::kCovariance);
  m = c;
  m(0, 1) = 1e-5;  // not symmetric
  EXPECT_EQ(check_covariance(m), StateFault::kCovariance);
  m = c;
  m(2, 2) = std::nan("");
  EXPECT_EQ(check_covariance(m), StateFault::kCovariance);
  EXPECT_EQ(check_covariance(Eigen::MatrixXd::Zero(6, 6)), StateFault::kCovariance);
}
