#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "liod/eval/evaluate.hpp"
#include "liod/eval/font.hpp"
#include "liod/eval/plot.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

TEST(Plot, NiceStepsAndLabels) {
  EXPECT_DOUBLE_EQ(nice_step(1000.0, 8), 200.0);
  EXPECT_DOUBLE_EQ(nice_step(7.0, 5), 2.0);
  EXPECT_DOUBLE_EQ(nice_step(0.03, 6), 0.005);
  EXPECT_EQ(tick_label(300.0, 100.0), "300");
  EXPECT_EQ(tick_label(-12.5, 2.5), "-12.5");
  EXPECT_EQ(tick_label(0.015, 0.005), "0.015");
  EXPECT_EQ(tick_label(-1e-17, 0.5), "0.0");
}

TEST(Plot, FontHasTheCharactersTheLabelsUse) {
  for (const char c : std::string("0123456789.-[]()%/:ABCDEFGHIJKLMNOPQRSTUVWXYZmsxyz ")) {
    EXPECT_NE(glyph(c), nullptr) << c;
  }
  EXPECT_EQ(glyph('~'), nullptr);
}

TEST(Plot, DrawsBothTrajectoriesAndWritesAPng) {
  const Trajectory gt = test::stamped(test::wiggly(300), 0.0, 0.1, "gt");
  Trajectory est = gt;
  for (std::size_t i = 0; i < est.size(); ++i) est.poses[i].translation().x() += 0.01 * static_cast<double>(i);
  const EvalResult r = evaluate(gt, est, {});
  const Canvas c = render_plot(r);
  std::size_t blue = 0;
  std::size_t red = 0;
  for (int y = 0; y < c.height(); ++y) {
    for (int x = 0; x < c.width(); ++x) {
      const Rgb p = c.at(x, y);
      blue += static_cast<std::size_t>(p.r == 0 && p.g == 114 && p.b == 189);
      red += static_cast<std::size_t>(p.r == 200 && p.g == 50 && p.b == 40);
    }
  }
  EXPECT_GT(blue, 1000U);  // the estimate's line
  EXPECT_GT(red, 500U);    // the error curve

  const auto path = std::filesystem::temp_directory_path() / "liod_eval_test" / "plot.png";
  std::filesystem::create_directories(path.parent_path());
  std::filesystem::remove(path);
  write_plot(path.string(), r);
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_THROW(write_plot("/nonexistent/dir/plot.png", r), std::runtime_error);
}

}  // namespace
}  // namespace liod::eval
