#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "liod/eval/io.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

/// Runs f, which must throw InputError, and returns its message.
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return {};
}

TEST(TumReader, ReadsPosesSkippingCommentsAndBlankLines) {
  const double h = std::sqrt(0.5);
  std::istringstream in(
      "# timestamp tx ty tz qx qy qz qw\n"
      "\n"
      "1.5 1 2 3 0 0 0 1\n"
      "  2.5\t4 5 6   0 0 " +
      std::to_string(h) + " " + std::to_string(h) + "  # 90 deg yaw\n");
  const Trajectory t = read_tum(in, "gt.txt");
  ASSERT_EQ(t.size(), 2U);
  EXPECT_EQ(t.stamps[0], 1.5);
  EXPECT_EQ(t.stamps[1], 2.5);
  EXPECT_TRUE(t.poses[0].translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  // qx qy qz qw order: a yaw of +90 deg turns x into y.
  EXPECT_NEAR((t.poses[1].linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-6);
  EXPECT_NEAR((t.poses[1].linear().transpose() * t.poses[1].linear() - Eigen::Matrix3d::Identity()).norm(), 0.0,
              1e-12);
}

TEST(TumReader, WrongColumnCountNamesFileAndLine) {
  std::istringstream in("0 0 0 0 0 0 0 1\n# ok\n1 0 0 0 0 0 1\n");
  const std::string msg = error_of([&] { read_tum(in, "est.txt"); });
  EXPECT_NE(msg.find("est.txt:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 8 numbers"), std::string::npos) << msg;
  EXPECT_NE(msg.find("got 7"), std::string::npos) << msg;
}

TEST(TumReader, NonNumberNamesLineAndToken) {
  std::istringstream in("0 0 0 0 0 0 0 1\n1 0 0 abc 0 0 0 1\n");
  const std::string msg = error_of([&] { read_tum(in, "est.txt"); });
  EXPECT_NE(msg.find("est.txt:2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'abc'"), std::string::npos) << msg;
}

TEST(TumReader, RejectsNanDecreasingTimeBadQuaternionAndEmptyFile) {
  std::istringstream nan_in("0 nan 0 0 0 0 0 1\n");
  EXPECT_NE(error_of([&] { read_tum(nan_in, "a"); }).find("a:1:"), std::string::npos);
  std::istringstream back("1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n");
  const std::string msg = error_of([&] { read_tum(back, "b"); });
  EXPECT_NE(msg.find("b:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("does not increase"), std::string::npos) << msg;
  // w first (qw qx qy qz) is a common mistake; an all-zero quaternion is caught by its norm.
  std::istringstream quat("0 0 0 0 0 0 0 0\n");
  EXPECT_NE(error_of([&] { read_tum(quat, "c"); }).find("quaternion norm"), std::string::npos);
  std::istringstream empty("# nothing\n\n");
  EXPECT_NE(error_of([&] { read_tum(empty, "d"); }).find("no poses"), std::string::npos);
}

TEST(TumReader, MissingFileIsNamed) {
  const std::string msg = error_of([] { read_tum("/nonexistent/liod/gt.txt"); });
  EXPECT_NE(msg.find("/nonexistent/liod/gt.txt"), std::string::npos) << msg;
}

TEST(KittiReader, ReadsRowMajorRotationAndTranslation) {
  // Yaw of +90 deg about z: R = [0 -1 0; 1 0 0; 0 0 1], t = (10, 20, 30).
  std::istringstream in("1 0 0 0 0 1 0 0 0 0 1 0\n0 -1 0 10 1 0 0 20 0 0 1 30\n");
  const Trajectory t = read_kitti(in, "kitti.txt");
  ASSERT_EQ(t.size(), 2U);
  EXPECT_FALSE(t.has_stamps());
  EXPECT_TRUE(t.poses[1].translation().isApprox(Eigen::Vector3d(10, 20, 30)));
  EXPECT_NEAR((t.poses[1].linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
}

TEST(KittiReader, ProjectsRoundedRotationsOntoSO3) {
  // Six significant digits, as in KITTI's poses files.
  std::istringstream in("0.999999 0.001 0 1 -0.001 0.999999 0 2 0 0 1 3\n");
  const Trajectory t = read_kitti(in, "k");
  const Eigen::Matrix3d R = t.poses[0].linear();
  EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(KittiReader, MalformedLinesAreNamed) {
  std::istringstream short_line("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  const std::string msg = error_of([&] { read_kitti(short_line, "poses.txt"); });
  EXPECT_NE(msg.find("poses.txt:2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 12 numbers"), std::string::npos) << msg;
  std::istringstream not_rotation("2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(error_of([&] { read_kitti(not_rotation, "p"); }).find("not a rotation"), std::string::npos);
  std::istringstream mirror("-1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_NE(error_of([&] { read_kitti(mirror, "p"); }).find("p:1:"), std::string::npos);
}

TEST(TimesReader, ReadsOneStampPerLine) {
  std::istringstream in("0.000000e+00\n1.036742e-01\n2.072496e-01\n");
  const auto stamps = read_times(in, "times.txt");
  ASSERT_EQ(stamps.size(), 3U);
  EXPECT_DOUBLE_EQ(stamps[1], 0.1036742);
  std::istringstream bad("0\n0.1 0.2\n");
  EXPECT_NE(error_of([&] { read_times(bad, "times.txt"); }).find("times.txt:2:"), std::string::npos);
}

TEST(FormatDetection, ByColumnCount) {
  const std::string tum = test::write_temp("detect_tum.txt", "# c\n0 1 2 3 0 0 0 1\n");
  const std::string kitti = test::write_temp("detect_kitti.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  const std::string odd = test::write_temp("detect_odd.txt", "1 2 3\n");
  EXPECT_EQ(detect_format(tum), Format::Tum);
  EXPECT_EQ(detect_format(kitti), Format::Kitti);
  EXPECT_NE(error_of([&] { detect_format(odd); }).find(odd + ":1:"), std::string::npos);
}

TEST(Writers, RoundTripThroughReaders) {
  Trajectory t = test::stamped(test::wiggly(20), 100.0, 0.1, "w");
  std::stringstream tum;
  write_tum(tum, t);
  const Trajectory back = read_tum(tum, "w");
  ASSERT_EQ(back.size(), t.size());
  std::stringstream kitti;
  write_kitti(kitti, t);
  const Trajectory kback = read_kitti(kitti, "w");
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(back.stamps[i], t.stamps[i], 1e-12);
    EXPECT_TRUE(back.poses[i].isApprox(t.poses[i], 1e-12));
    EXPECT_TRUE(kback.poses[i].isApprox(t.poses[i], 1e-12));
  }
}

}  // namespace
}  // namespace liod::eval
