#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "liod/eval/evaluate.hpp"
#include "liod/eval/plot.hpp"
#include "synthetic.hpp"

namespace liod::eval {
namespace {

// The ground truth and an estimate whose error grows along the path, so the colour scale spans a range.
EvalResult drifting_estimate() {
  const Trajectory gt = test::stamped(test::wiggly(300), 0.0, 0.1, "gt.tum");
  Trajectory est = gt;
  est.name = "est.tum";
  for (std::size_t i = 0; i < est.size(); ++i) est.poses[i].translation().x() += 0.01 * static_cast<double>(i);
  return evaluate(gt, est, {});
}

std::vector<std::vector<double>> csv_rows(std::istream& in, std::string& header) {
  std::vector<std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) {
      header = line;
      continue;
    }
    std::vector<double> row;
    std::stringstream fields(line);
    for (std::string f; std::getline(fields, f, ',');) row.push_back(std::stod(f));
    rows.push_back(row);
  }
  return rows;
}

TEST(Plot, PairsHoldTheGroundTruthTheAlignedEstimateAndTheError) {
  const EvalResult r = drifting_estimate();
  std::stringstream s;
  write_pairs(s, r);
  EXPECT_NE(s.str().find("# alignment=se3\n"), std::string::npos);
  EXPECT_NE(s.str().find("# est=est.tum\n"), std::string::npos);
  std::string header;
  const auto rows = csv_rows(s, header);
  EXPECT_EQ(header, kPairsHeader);
  ASSERT_EQ(rows.size(), r.association.gt.size());
  for (std::size_t i = 0; i < rows.size(); i += 37) {
    ASSERT_EQ(rows[i].size(), 10U);
    EXPECT_NEAR(rows[i][0], r.association.stamps[i], 1e-9);
    EXPECT_NEAR(rows[i][2], r.association.gt[i].translation().x(), 1e-7);
    EXPECT_NEAR(rows[i][7], r.est_aligned[i].translation().z(), 1e-7);
    EXPECT_NEAR(rows[i][8], r.ate.translation_m[i], 1e-9);
    EXPECT_NEAR(rows[i][9], r.ate.rotation_deg[i], 1e-9);
  }
  EXPECT_DOUBLE_EQ(rows.front()[1], 0.0);
  EXPECT_NEAR(rows.back()[1], r.length_m, 1e-6);
}

std::array<unsigned, 2> png_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 24> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  // Signature, then the IHDR chunk: length, "IHDR", big-endian width and height (PNG spec, 11.2.2).
  const std::array<unsigned char, 8> signature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!in || !std::equal(signature.begin(), signature.end(), head.begin()) ||
      std::string(reinterpret_cast<const char*>(head.data()) + 12, 4) != "IHDR") {
    return {0, 0};
  }
  const auto be32 = [&](int at) {
    return (unsigned{head[at]} << 24U) | (unsigned{head[at + 1]} << 16U) | (unsigned{head[at + 2]} << 8U) |
           unsigned{head[at + 3]};
  };
  return {be32(16), be32(20)};
}

std::string run_output(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe) != nullptr) out += buf.data();
  pclose(pipe);
  return out;
}

TEST(Plot, TheScriptDrawsEveryPairColouredByItsError) {
  const EvalResult r = drifting_estimate();
  const liod::test::ScratchDir dir("plot");
  const std::string png = (dir / "plot.png").string();
  write_plot(png, r);
  const auto [width, height] = png_size(png);
  EXPECT_EQ(width, 1300U);
  EXPECT_EQ(height, 1100U);

  // The script's account of what it drew: every pair, the colour scale spanning the error.
  const std::string pairs = (dir / "pairs.csv").string();
  write_pairs(pairs, r);
  const std::string out = run_output("'" + default_plot_script() + "' '" + pairs + "' '" + png + "' --summary");
  ASSERT_FALSE(out.empty());
  const auto summary = nlohmann::json::parse(out);
  EXPECT_EQ(summary["plane"], "xy");
  EXPECT_EQ(summary["pairs"].get<std::size_t>(), r.ate.translation_m.size());
  EXPECT_NEAR(summary["colour_limits"][0].get<double>(), r.ate.translation.min, 1e-6);
  EXPECT_NEAR(summary["colour_limits"][1].get<double>(), r.ate.translation.max, 1e-6);
  EXPECT_NEAR(summary["rmse_m"].get<double>(), r.ate.translation.rmse, 1e-6);
}

TEST(Plot, FailuresAreErrorsNamingTheCause) {
  const EvalResult r = drifting_estimate();
  EXPECT_THROW(write_plot("/nonexistent/dir/plot.png", r), std::runtime_error);
  PlotOptions missing;
  missing.script = "/nonexistent/liod-eval-plot";
  try {
    write_plot("plot.png", r, missing);
    ADD_FAILURE() << "no error for a missing script";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/liod-eval-plot"), std::string::npos) << e.what();
  }
  // A file that is not liod-eval's pairs: the script refuses it, naming the line.
  const liod::test::ScratchDir dir("plot-bad");
  const std::string bad = (dir / "bad.csv").string();
  std::ofstream(bad) << "t,x,y\n1,2,3\n";
  const std::string err =
      run_output("'" + default_plot_script() + "' '" + bad + "' '" + (dir / "x.png").string() + "' 2>&1");
  EXPECT_NE(err.find("bad.csv:1: expected the header"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

}  // namespace
}  // namespace liod::eval
