// The backend end to end on a synthetic city block driven 1.4 times with a drifting odometry:
// keyframes in, loops detected and verified, the graph re-optimised, and the corrected
// trajectory closer to the truth than the odometry.

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "liod/angles.hpp"
#include "liod/backend/backend.hpp"
#include "liod/backend/map_store.hpp"
#include "synthetic_world.hpp"

namespace {

using namespace liod;
test::World city_block() {
  test::World w;
  std::mt19937 rng(21);
  test::add_ground(w, -20, 80, -20, 80, 0.0, 0.3);
  // The block inside the square route and the buildings outside it, facing the roads.
  test::add_facade_row(w, 5, 55, 7.0, 1.0, rng, 0.25);     // inside, along the south road
  test::add_facade_row(w, 5, 55, 53.0, -1.0, rng, 0.25);   // inside, along the north road
  test::add_facade_row(w, 0, 60, -7.0, -1.0, rng, 0.25);   // outside south
  test::add_facade_row(w, 0, 60, 67.0, 1.0, rng, 0.25);    // outside north
  for (double y = 12; y < 50; y += 9) {
    test::add_box(w, {Eigen::Vector3d(7, y, 0), Eigen::Vector3d(12, y + 6, 8)}, 0.25);     // inside west
    test::add_box(w, {Eigen::Vector3d(48, y, 0), Eigen::Vector3d(53, y + 5, 6)}, 0.25);    // inside east
    test::add_box(w, {Eigen::Vector3d(-13, y, 0), Eigen::Vector3d(-7, y + 7, 10)}, 0.25);  // outside west
    test::add_box(w, {Eigen::Vector3d(67, y + 2, 0), Eigen::Vector3d(73, y + 6, 7)}, 0.25); // outside east
  }
  return w;
}

// Counter-clockwise around the 60 m square (0,0)-(60,60), 2 m per keyframe.
Eigen::Isometry3d route(double s) {
  const double side = 60.0;
  const double lap = 4 * side;
  s = std::fmod(s, lap);
  const int k = static_cast<int>(s / side);
  const double u = s - k * side;
  const double corners[4][2] = {{0, 0}, {side, 0}, {side, side}, {0, side}};
  const double yaw = k * 90.0 * kDegToRad;
  Eigen::Isometry3d t = test::pose_xyz_yaw(corners[k][0], corners[k][1], 0.0, yaw);
  t.translation() += u * t.linear().col(0);
  return t;
}

TEST(Backend, ClosesTheLoopAroundABlockAndRemovesTheDrift) {
  const test::World world = city_block();
  AlgorithmConfig config;
  config.backend.enabled = true;
  Backend backend(config);
  std::vector<Eigen::Isometry3d> truth;
  std::vector<Eigen::Isometry3d> odometry;
  std::vector<NavState> odometry_states;
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.01);
  int loops = 0;
  const int keyframes = 170;  // 340 m: 1.4 laps
  for (int i = 0; i < keyframes; ++i) {
    truth.push_back(route(2.0 * i));
    if (i == 0) {
      odometry.push_back(truth[0]);
    } else {
      // A gyro bias: 0.04 deg of extra yaw per keyframe, plus noise.
      Eigen::Isometry3d step = truth[i - 1].inverse() * truth[i];
      step.linear() = Eigen::AngleAxisd(0.04 * kDegToRad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * step.linear();
      step.translation() += Eigen::Vector3d(noise(rng), noise(rng), 0.3 * noise(rng));
      odometry.push_back(odometry.back() * step);
    }
    const Keyframe k = test::make_keyframe(world, truth[i], odometry[i], static_cast<std::uint64_t>(i), 0.2 * i);
    odometry_states.push_back(k.state);
    if (backend.add_keyframe(k)) ++loops;
  }
  double before = 0.0;
  double after = 0.0;
  const auto optimized = backend.optimized_keyframe_poses();
  for (int i = 0; i < keyframes; ++i) {
    before += (odometry[i].translation() - truth[i].translation()).squaredNorm();
    after += (optimized[i].translation() - truth[i].translation()).squaredNorm();
  }
  before = std::sqrt(before / keyframes);
  after = std::sqrt(after / keyframes);
  const auto& stats = backend.stats();
  double check_ms = 0.0;
  for (double ms : stats.check_ms) check_ms += ms;
  double solve_ms = 0.0;
  for (double ms : stats.solve_ms) solve_ms += ms;
  std::printf("keyframe rms error %.3f m -> %.3f m; %zu loops, %zu rejected; %zu checks %.0f ms, %zu solves %.0f ms\n",
              before, after, stats.loops_accepted, stats.loops_rejected, stats.check_ms.size(), check_ms,
              stats.solve_ms.size(), solve_ms);
  for (std::size_t i = 0; i < stats.outcomes.size(); ++i) {
    std::printf("  %s: %zu\n", to_string(static_cast<LoopOutcome>(i)), stats.outcomes[i]);
  }
  EXPECT_GE(loops, 2);
  EXPECT_EQ(stats.loops_accepted, static_cast<std::size_t>(loops));
  EXPECT_EQ(stats.solve_ms.size(), stats.loops_accepted);
  EXPECT_GT(before, 1.0);
  // What remains is the least-squares share of a systematic heading drift along the stretch
  // of the first lap that no loop touches.
  EXPECT_LT(after, 0.45) << "before " << before << ", loops " << loops;
  EXPECT_LT(after, before / 4.0);

  // The loops hold: the optimised poses keep every accepted loop's relative pose as close to the
  // truth as the registration measured it (the synthetic scans are exact, so the registration is
  // good to ~1 cm / 0.05 deg). Loop weights looser than that let the odometry's accumulated
  // drift pull the loop keyframes apart again.
  double worst_loop_m = 0.0;
  double worst_loop_deg = 0.0;
  for (const LoopCheck& check : backend.loop_checks()) {
    if (check.outcome != LoopOutcome::kAccepted) continue;
    const Eigen::Isometry3d solved = optimized[check.candidate].inverse() * optimized[check.current];
    const Eigen::Isometry3d true_relative = truth[check.candidate].inverse() * truth[check.current];
    const Eigen::Isometry3d error = true_relative.inverse() * solved;
    worst_loop_m = std::max(worst_loop_m, error.translation().norm());
    worst_loop_deg = std::max(worst_loop_deg, Eigen::AngleAxisd(error.linear()).angle() / kDegToRad);
  }
  std::printf("worst loop error after the solve: %.3f m, %.3f deg\n", worst_loop_m, worst_loop_deg);
  EXPECT_LT(worst_loop_m, 0.08);
  EXPECT_LT(worst_loop_deg, 0.1);  // 0.30 deg with the former 0.1 m / 0.5 deg loop sigmas

  // The corrected trajectory at the keyframe times is the optimised keyframe poses, and the
  // newest keyframe's correction maps its odometry pose onto its optimised pose.
  const auto corrected = backend.corrected_trajectory(odometry_states);
  for (int i = 0; i < keyframes; i += 17) {
    EXPECT_LT((corrected[i].position - optimized[i].translation()).norm(), 1e-9) << i;
  }
  EXPECT_TRUE((backend.correction() * odometry.back()).isApprox(optimized.back(), 1e-9));
  // A pose half-way between two keyframes gets the interpolated correction.
  NavState mid = odometry_states[100];
  mid.time += 0.1;
  mid.position = 0.5 * (odometry_states[100].position + odometry_states[101].position);
  const auto corrected_mid = backend.corrected_trajectory({mid});
  EXPECT_LT((corrected_mid[0].position - 0.5 * (optimized[100].translation() + optimized[101].translation())).norm(), 0.02);
}

TEST(Backend, NoLoopWithoutARevisit) {
  const test::World world = city_block();
  AlgorithmConfig config;
  config.backend.enabled = true;
  Backend backend(config);
  for (int i = 0; i < 100; ++i) {  // 200 m: most of a lap, never back at the start
    const auto pose = route(2.0 * i);
    EXPECT_FALSE(backend.add_keyframe(test::make_keyframe(world, pose, pose, static_cast<std::uint64_t>(i), 0.2 * i)));
  }
  EXPECT_EQ(backend.stats().loops_accepted, 0U);
  EXPECT_TRUE(backend.correction().isApprox(Eigen::Isometry3d::Identity(), 1e-9));
}

// Bounded memory: with 30 clouds in memory and the rest in a scratch directory, the loop checks
// read the candidates' sub-maps back from disk, and the backend finds the same loops and the same
// optimised poses, bit for bit, as with every cloud in memory; so does the global map.
TEST(Backend, SameLoopsAndPosesWithMostCloudsOnDisk) {
  const test::World world = city_block();
  AlgorithmConfig config;
  config.backend.enabled = true;
  config.backend.memory_keyframes = 30;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("liod_backend_spill_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  Backend in_memory(config);
  Backend spilling(config, std::make_shared<KeyframeDirectory>(dir, KeyframeDirectory::Kind::kScratch));
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::Isometry3d odometry = route(0.0);
  std::size_t most_in_memory = 0;
  const int keyframes = 170;
  for (int i = 0; i < keyframes; ++i) {
    const Eigen::Isometry3d truth = route(2.0 * i);
    if (i > 0) {
      Eigen::Isometry3d step = route(2.0 * (i - 1)).inverse() * truth;
      step.linear() = Eigen::AngleAxisd(0.04 * kDegToRad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * step.linear();
      step.translation() += Eigen::Vector3d(noise(rng), noise(rng), 0.3 * noise(rng));
      odometry = odometry * step;
    }
    const Keyframe k = test::make_keyframe(world, truth, odometry, static_cast<std::uint64_t>(i), 0.2 * i);
    EXPECT_EQ(in_memory.add_keyframe(k), spilling.add_keyframe(k)) << i;
    most_in_memory = std::max(most_in_memory, spilling.keyframes().in_memory_count());
  }
  const KeyframeStore& store = spilling.keyframes();
  std::printf("%zu loops; clouds in memory at most %zu of %zu, %zu evictions, %zu read back\n",
              spilling.stats().loops_accepted, most_in_memory, store.size(), store.evictions(), store.reads());
  EXPECT_GE(spilling.stats().loops_accepted, 2U);
  EXPECT_EQ(spilling.stats().loops_accepted, in_memory.stats().loops_accepted);
  EXPECT_EQ(spilling.stats().outcomes, in_memory.stats().outcomes);
  EXPECT_LE(most_in_memory, 30U);
  EXPECT_EQ(in_memory.keyframes().in_memory_count(), static_cast<std::size_t>(keyframes));
  EXPECT_GT(store.reads(), 0U);  // the loop checks did need evicted clouds
  const auto a = in_memory.optimized_keyframe_poses();
  const auto b = spilling.optimized_keyframe_poses();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(std::memcmp(a[i].matrix().data(), b[i].matrix().data(), 16 * sizeof(double)), 0) << i;
  }
  const auto map_a = in_memory.global_map(0.3);
  const auto map_b = spilling.global_map(0.3);
  ASSERT_EQ(map_a.size(), map_b.size());
  EXPECT_GT(map_a.size(), 1000U);
  EXPECT_EQ(std::memcmp(map_a.data(), map_b.data(), map_a.size() * sizeof(Eigen::Vector3d)), 0);
  EXPECT_EQ(store.in_memory_count(), 30U);  // the map sweep leaves the cache alone
}

}  // namespace
