#include "liod/eval/plot.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

#include "liod/eval/io.hpp"

namespace liod::eval {
namespace {

constexpr Rgb kInk{30, 30, 30};
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kGt{40, 40, 40};
constexpr Rgb kEst{0, 114, 189};
constexpr Rgb kErr{200, 50, 40};
constexpr Rgb kStart{0, 160, 60};
constexpr int kText = 2;  // glyph scale: 10x14 pixel characters

struct Box {
  int left, top, right, bottom;  // pixel bounds of the data area, inclusive
};

/// Data-to-pixel mapping of one panel.
struct Axes {
  Box box;
  double x0, x1, y0, y1;  // data range shown
  [[nodiscard]] double px(double x) const { return box.left + (x - x0) / (x1 - x0) * (box.right - box.left); }
  [[nodiscard]] double py(double y) const { return box.bottom - (y - y0) / (y1 - y0) * (box.bottom - box.top); }
};

std::array<int, 2> plane_axes(const std::string& plane, const Poses& gt) {
  if (plane == "xy") return {0, 1};
  if (plane == "xz") return {0, 2};
  if (plane == "yz") return {1, 2};
  if (plane != "auto") throw InputError("unknown plot plane '" + plane + "' (want auto, xy, xz or yz)");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : gt) {
    lo = lo.cwiseMin(p.translation());
    hi = hi.cwiseMax(p.translation());
  }
  const Eigen::Vector3d extent = hi - lo;
  Eigen::Index smallest = 2;
  extent.minCoeff(&smallest);
  // Ties (a flat or straight path) keep x-y, the top-down view of a z-up world.
  if (smallest == 2 || extent(2) <= extent(smallest)) return {0, 1};
  return smallest == 1 ? std::array<int, 2>{0, 2} : std::array<int, 2>{1, 2};
}

void frame_and_ticks(Canvas& c, const Axes& ax, double step_x, double step_y, const std::string& xlabel,
                     const std::string& ylabel) {
  const Box& b = ax.box;
  for (double v = std::ceil(ax.x0 / step_x) * step_x; v <= ax.x1 + 1e-9 * step_x; v += step_x) {
    const int x = static_cast<int>(std::lround(ax.px(v)));
    c.line(x, b.top, x, b.bottom, kGrid);
    c.line(x, b.bottom, x, b.bottom + 6, kInk);
    const std::string s = tick_label(v, step_x);
    c.text(x - Canvas::text_width(s, kText) / 2, b.bottom + 10, s, kInk, kText);
  }
  for (double v = std::ceil(ax.y0 / step_y) * step_y; v <= ax.y1 + 1e-9 * step_y; v += step_y) {
    const int y = static_cast<int>(std::lround(ax.py(v)));
    c.line(b.left, y, b.right, y, kGrid);
    c.line(b.left - 6, y, b.left, y, kInk);
    const std::string s = tick_label(v, step_y);
    c.text(b.left - 10 - Canvas::text_width(s, kText), y - Canvas::text_height(kText) / 2, s, kInk, kText);
  }
  c.line(b.left, b.top, b.right, b.top, kInk);
  c.line(b.left, b.bottom, b.right, b.bottom, kInk);
  c.line(b.left, b.top, b.left, b.bottom, kInk);
  c.line(b.right, b.top, b.right, b.bottom, kInk);
  c.text((b.left + b.right - Canvas::text_width(xlabel, kText)) / 2, b.bottom + 32, xlabel, kInk, kText);
  c.text(b.left, b.top - Canvas::text_height(kText) - 8, ylabel, kInk, kText);
}

void polyline(Canvas& c, const Axes& ax, const std::vector<Eigen::Vector2d>& pts, Rgb colour, int width) {
  for (std::size_t i = 1; i < pts.size(); ++i) {
    c.line(ax.px(pts[i - 1].x()), ax.py(pts[i - 1].y()), ax.px(pts[i].x()), ax.py(pts[i].y()), colour, width);
  }
}

void top_view(Canvas& c, const Box& box, const EvalResult& r, const PlotOptions& o) {
  const auto axes = plane_axes(o.plane, r.association.gt);
  const char* names = "xyz";
  std::vector<Eigen::Vector2d> gt;
  std::vector<Eigen::Vector2d> est;
  for (const auto& p : r.association.gt) gt.emplace_back(p.translation()(axes[0]), p.translation()(axes[1]));
  for (const auto& p : r.est_aligned) est.emplace_back(p.translation()(axes[0]), p.translation()(axes[1]));

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto* v : {&gt, &est}) {
    for (const auto& p : *v) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  // Equal scale: one metre is the same number of pixels on both axes, so shapes are not distorted.
  const double span_px_x = box.right - box.left;
  const double span_px_y = box.bottom - box.top;
  double range = std::max({(hi - lo).x() / span_px_x, (hi - lo).y() / span_px_y, 1e-6}) * 1.08;
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  Axes ax{box, mid.x() - range * span_px_x / 2, mid.x() + range * span_px_x / 2, mid.y() - range * span_px_y / 2,
          mid.y() + range * span_px_y / 2};
  const double step = nice_step(std::max(ax.x1 - ax.x0, ax.y1 - ax.y0), 8);
  const std::string x_label = std::string(1, names[axes[0]]) + " [m]";
  const std::string y_label = std::string(1, names[axes[1]]) + " [m]";
  frame_and_ticks(c, ax, step, step, x_label, y_label);
  polyline(c, ax, gt, kGt, 2);
  polyline(c, ax, est, kEst, 2);
  c.disc(ax.px(gt.front().x()), ax.py(gt.front().y()), 7, kStart);

  // Legend in one row above the panel, so it never hides a part of the path.
  std::string mode = to_string(r.alignment.options.mode);
  for (auto& ch : mode) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  int lx = box.right - 560;
  const int ly = box.top - Canvas::text_height(kText) - 8;
  c.line(lx, ly + 6, lx + 30, ly + 6, kGt, 3);
  c.text(lx + 38, ly, "GROUND TRUTH", kInk, kText);
  lx += 38 + Canvas::text_width("GROUND TRUTH", kText) + 24;
  c.line(lx, ly + 6, lx + 30, ly + 6, kEst, 3);
  const std::string est_label = "ESTIMATE (" + mode + ")";
  c.text(lx + 38, ly, est_label, kInk, kText);
  lx += 38 + Canvas::text_width(est_label, kText) + 24;
  c.disc(lx + 6, ly + 6, 7, kStart);
  c.text(lx + 20, ly, "START", kInk, kText);
}

void error_panel(Canvas& c, const Box& box, const EvalResult& r) {
  const std::vector<double> dist = path_distances(r.association.gt);
  const auto& err = r.ate.translation_m;
  const double x1 = std::max(dist.back(), 1e-6);
  const double y1 = std::max(*std::max_element(err.begin(), err.end()), 1e-6) * 1.1;
  const Axes ax{box, 0.0, x1, 0.0, y1};
  frame_and_ticks(c, ax, nice_step(x1, 8), nice_step(y1, 5), "DISTANCE TRAVELLED [m]", "ATE TRANSLATION [m]");
  std::vector<Eigen::Vector2d> pts;
  for (std::size_t i = 0; i < err.size(); ++i) pts.emplace_back(dist[i], err[i]);
  polyline(c, ax, pts, kErr, 2);
  if (pts.size() == 1) c.disc(ax.px(pts[0].x()), ax.py(pts[0].y()), 3, kErr);
}

}  // namespace

double nice_step(double range, int target) {
  if (!(range > 0.0) || !std::isfinite(range)) return 1.0;
  const double raw = range / std::max(target, 1);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

std::string tick_label(double value, double step) {
  // Fewest decimals that show every multiple of the step exactly (2.5 needs one, 0.005 three).
  int decimals = 0;
  for (double scaled = std::abs(step); decimals < 6; ++decimals, scaled *= 10.0) {
    if (std::abs(scaled - std::round(scaled)) < 1e-6 * std::max(scaled, 1.0)) break;
  }
  if (std::abs(value) < step * 1e-6) value = 0.0;  // no "-0"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

Canvas render_plot(const EvalResult& result, const PlotOptions& options) {
  Canvas c(options.width, options.height);
  const int split = options.height * 7 / 10;
  c.text(20, 14, "TRAJECTORY, TOP VIEW", kInk, kText);
  top_view(c, {120, 70, options.width - 40, split - 70}, result, options);
  error_panel(c, {120, split + 40, options.width - 40, options.height - 70}, result);
  return c;
}

void write_plot(const std::string& path, const EvalResult& result, const PlotOptions& options) {
  render_plot(result, options).write_png(path);
}

}  // namespace liod::eval
