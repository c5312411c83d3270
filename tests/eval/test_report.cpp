#include <gtest/gtest.h>

#include "liod/eval/evaluate.hpp"
#include "liod/eval/report.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

EvalResult small_result() {
  // ~44 m of wiggly path at 10 Hz, estimate shifted 0.3 m sideways, no alignment.
  const Trajectory gt = test::stamped(test::wiggly(120, 0.5), 10.0, 0.1, "gt.txt");
  Trajectory est = gt;
  est.name = "est.txt";
  for (auto& p : est.poses) p.translation().y() += 0.3;
  EvalOptions o;
  o.alignment.mode = AlignMode::None;
  return evaluate(gt, est, o);
}

TEST(Report, JsonCarriesTheFiguresUnderStableKeys) {
  const nlohmann::json j = to_json(small_result());
  EXPECT_NEAR(j["ate"]["rmse_m"].get<double>(), 0.3, 1e-12);
  EXPECT_NEAR(j["ate"]["max_m"].get<double>(), 0.3, 1e-12);
  EXPECT_NEAR(j["ate"]["rot_rmse_deg"].get<double>(), 0.0, 1e-9);
  EXPECT_EQ(j["poses_associated"].get<std::size_t>(), 120U);
  EXPECT_NEAR(j["duration_s"].get<double>(), 11.9, 1e-9);
  EXPECT_GT(j["length_m"].get<double>(), 30.0);
  EXPECT_LT(j["length_m"].get<double>(), 100.0);
  EXPECT_NEAR(j["distance"]["error_pct"].get<double>(), 0.0, 1e-9);  // shifted sideways, as far travelled
  EXPECT_EQ(j["alignment"]["mode"], "none");
  EXPECT_EQ(j["association"]["method"], "nearest");
  EXPECT_EQ(j["rpe"]["delta_unit"], "s");
  EXPECT_NEAR(j["rpe"]["trans_max_m"].get<double>(), 0.0, 1e-12);
  // Shorter than 100 m: the KITTI figures are null, not 0, and a note says why.
  EXPECT_TRUE(j["kitti"]["translational_pct"].is_null());
  EXPECT_TRUE(j["kitti"]["rotational_deg_per_100m"].is_null());
  ASSERT_FALSE(j["notes"].empty());
  EXPECT_NE(j["notes"].dump().find("KITTI metric not computed"), std::string::npos);
}

TEST(Report, TableShowsUnitsAndNotApplicable) {
  const std::string t = format_table(small_result());
  EXPECT_NE(t.find("ATE trans [m]"), std::string::npos) << t;
  EXPECT_NE(t.find("ATE rot [deg]"), std::string::npos) << t;
  EXPECT_NE(t.find("RPE trans [m]"), std::string::npos) << t;
  EXPECT_NE(t.find("rot [deg/100m]"), std::string::npos) << t;
  EXPECT_NE(t.find("n/a"), std::string::npos) << t;
  EXPECT_NE(t.find("0.3000"), std::string::npos) << t;
}

}  // namespace
}  // namespace liod::eval
