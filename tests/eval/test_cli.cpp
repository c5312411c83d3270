#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "liod/eval/cli.hpp"
#include "liod/eval/io.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

struct CliRun {
  int code;
  std::string out;
  std::string err;
};

CliRun invoke(const std::vector<std::string>& args) {
  std::vector<const char*> argv{"liod-eval"};
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out;
  std::ostringstream err;
  const int code = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return {code, out.str(), err.str()};
}

std::string tum_file(const std::string& name, const Trajectory& t) {
  std::ostringstream s;
  write_tum(s, t);
  return test::write_temp(name, s.str());
}

TEST(Cli, JsonOnATumPair) {
  // 200 Hz ground truth, 10 Hz estimate with a 2 m offset: interpolation is chosen, se3 removes the offset.
  const Trajectory gt = test::stamped(test::wiggly(4001, 0.25), 0.0, 0.005, "gt");
  Trajectory est;
  for (std::size_t i = 0; i < gt.size(); i += 20) {
    est.stamps.push_back(gt.stamps[i]);
    est.poses.push_back(Eigen::Translation3d(2, 0, 0) * gt.poses[i]);
  }
  const CliRun r = invoke({"--gt", tum_file("cli_gt.txt", gt), "--est", tum_file("cli_est.txt", est), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["association"]["method"], "interpolated");
  EXPECT_EQ(j["poses_associated"].get<std::size_t>(), 201U);
  EXPECT_NEAR(j["ate"]["rmse_m"].get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(j["duration_s"].get<double>(), 20.0, 1e-9);
  EXPECT_FALSE(j["kitti"]["translational_pct"].is_null());  // ~600 m of path
  EXPECT_NEAR(j["kitti"]["translational_pct"].get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(j["distance"]["error_pct"].get<double>(), 0.0, 1e-9);  // a rigid offset travels as far
  EXPECT_NEAR(j["distance"]["ground_truth_m"].get<double>(), j["length_m"].get<double>(), 0.05 * j["length_m"].get<double>());

  const CliRun none = invoke({"--gt", tum_file("cli_gt.txt", gt), "--est", tum_file("cli_est.txt", est), "--json",
                        "--align", "none"});
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_NEAR(nlohmann::json::parse(none.out)["ate"]["rmse_m"].get<double>(), 2.0, 1e-9);
}

TEST(Cli, TableIsTheDefault) {
  const Trajectory gt = test::stamped(test::wiggly(50), 0.0, 0.1, "gt");
  const CliRun r = invoke({"--gt", tum_file("cli_t_gt.txt", gt), "--est", tum_file("cli_t_est.txt", gt)});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ATE trans [m]"), std::string::npos) << r.out;
}

TEST(Cli, KittiFilesPairByIndexAndRpeFallsBackToFrames) {
  const Trajectory gt = test::stamped(test::wiggly(30), 0.0, 0.1, "gt");
  std::ostringstream s;
  write_kitti(s, gt);
  const std::string path = test::write_temp("cli_kitti.txt", s.str());
  const CliRun r = invoke({"--gt", path, "--est", path, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["association"]["method"], "index");
  EXPECT_TRUE(j["duration_s"].is_null());
  EXPECT_EQ(j["rpe"]["delta_unit"], "frames");
  // With a times file the same poses pair by time.
  std::string times;
  for (int i = 0; i < 30; ++i) times += std::to_string(0.1 * i) + "\n";
  const std::string tpath = test::write_temp("cli_times.txt", times);
  const CliRun t = invoke({"--gt", path, "--est", path, "--gt-times", tpath, "--est-times", tpath, "--json"});
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_EQ(nlohmann::json::parse(t.out)["association"]["method"], "nearest");
}

TEST(Cli, TheSplitsVerticalIsZForTumAndMinusYForKitti) {
  // The estimate 0.4 m above a straight track: up in a TUM (z-up) world, and in a KITTI camera
  // world (y down) the same offset written as -0.4 m in y.
  Poses track;
  for (int i = 0; i < 40; ++i) track.push_back(test::pose(i, 0, 0));
  Trajectory gt = test::stamped(track, 0.0, 0.1, "gt");
  Trajectory est = gt;
  for (auto& p : est.poses) p.translation().z() += 0.4;
  const CliRun tum = invoke({"--gt", tum_file("cli_s_gt.txt", gt), "--est", tum_file("cli_s_est.txt", est), "--json",
                             "--align", "none"});
  ASSERT_EQ(tum.code, 0) << tum.err;
  const auto j = nlohmann::json::parse(tum.out);
  EXPECT_NEAR(j["ate_split"]["up_mean_m"].get<double>(), 0.4, 1e-9);
  EXPECT_NEAR(j["ate_split"]["along_rmse_m"].get<double>(), 0.0, 1e-9);

  Poses camera_track;  // KITTI: the camera looks along z
  for (int i = 0; i < 40; ++i) camera_track.push_back(test::pose(0, 0, i));
  Trajectory kgt = test::stamped(camera_track, 0.0, 0.1, "gt");
  Trajectory kest = kgt;
  for (auto& p : kest.poses) p.translation().y() -= 0.4;
  std::ostringstream gs;
  std::ostringstream es;
  write_kitti(gs, kgt);
  write_kitti(es, kest);
  const std::string kg = test::write_temp("cli_s_kgt.txt", gs.str());
  const std::string ke = test::write_temp("cli_s_kest.txt", es.str());
  const CliRun kitti = invoke({"--gt", kg, "--est", ke, "--json", "--align", "none"});
  ASSERT_EQ(kitti.code, 0) << kitti.err;
  EXPECT_NEAR(nlohmann::json::parse(kitti.out)["ate_split"]["up_mean_m"].get<double>(), 0.4, 1e-9);
  // Told that y is up, the same files read the offset as 0.4 m down.
  const CliRun told = invoke({"--gt", kg, "--est", ke, "--json", "--align", "none", "--up", "y"});
  ASSERT_EQ(told.code, 0) << told.err;
  EXPECT_NEAR(nlohmann::json::parse(told.out)["ate_split"]["up_mean_m"].get<double>(), -0.4, 1e-9);
  // The table prints the three rows.
  const CliRun table = invoke({"--gt", kg, "--est", ke, "--align", "none"});
  EXPECT_NE(table.out.find("ATE along [m]"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("ATE up [m]"), std::string::npos) << table.out;
}

TEST(Cli, BadInputExitsNonZeroWithAClearMessage) {
  const Trajectory gt = test::stamped(test::wiggly(20), 0.0, 0.1, "gt");
  const std::string good = tum_file("cli_good.txt", gt);
  const CliRun missing = invoke({"--gt", "/nonexistent/gt.txt", "--est", good});
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("/nonexistent/gt.txt: cannot open"), std::string::npos) << missing.err;

  const std::string bad = test::write_temp("cli_bad.txt", "0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n");
  const CliRun parse = invoke({"--gt", good, "--est", bad});
  EXPECT_EQ(parse.code, 1);
  EXPECT_NE(parse.err.find(bad + ":2:"), std::string::npos) << parse.err;

  const Trajectory later = test::stamped(test::wiggly(20), 1000.0, 0.1, "later");
  const CliRun overlap = invoke({"--gt", good, "--est", tum_file("cli_later.txt", later)});
  EXPECT_EQ(overlap.code, 1);
  EXPECT_NE(overlap.err.find("no overlap in time"), std::string::npos) << overlap.err;

  EXPECT_NE(invoke({"--gt", good}).code, 0);                                 // --est missing
  EXPECT_NE(invoke({"--gt", good, "--est", good, "--align", "affine"}).code, 0);  // not a mode
  EXPECT_EQ(invoke({"--help"}).code, 0);
}

}  // namespace
}  // namespace liod::eval
