#include "liod/sim/path.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace liod::sim {

std::vector<Eigen::Vector2d> rounded_polyline(const std::vector<Eigen::Vector2d>& corners,
                                              double radius, double spacing) {
  // First build exact geometry pieces (segments and arcs), then sample them evenly.
  std::vector<Eigen::Vector2d> out;
  if (corners.size() < 2) {
    return corners;
  }
  Eigen::Vector2d cursor = corners.front();
  out.push_back(cursor);
  double carry = 0.0;  // distance already covered since the last emitted point
  auto emit_line = [&](const Eigen::Vector2d& to) {
    const Eigen::Vector2d d = to - cursor;
    const double len = d.norm();
    if (len < 1e-9) {
      return;
    }
    double t = spacing - carry;
    while (t <= len) {
      out.push_back(cursor + d * (t / len));
      t += spacing;
    }
    carry = len - (t - spacing);
    cursor = to;
  };
  for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
    const Eigen::Vector2d a = corners[i - 1];
    const Eigen::Vector2d b = corners[i];
    const Eigen::Vector2d c = corners[i + 1];
    const Eigen::Vector2d d1 = (b - a).normalized();
    const Eigen::Vector2d d2 = (c - b).normalized();
    const double cross = d1.x() * d2.y() - d1.y() * d2.x();
    const double turn = std::atan2(cross, d1.dot(d2));
    if (std::abs(turn) < 1e-6) {
      continue;
    }
    const double max_tan = 0.45 * std::min((b - a).norm(), (c - b).norm());
    const double r = std::min(radius, max_tan / std::tan(std::abs(turn) / 2.0));
    const double tan_len = r * std::tan(std::abs(turn) / 2.0);
    const Eigen::Vector2d start = b - d1 * tan_len;
    emit_line(start);
    // Walk the arc in small steps so the spacing stays even.
    const Eigen::Vector2d left(-d1.y(), d1.x());
    const double side = turn > 0.0 ? 1.0 : -1.0;
    const Eigen::Vector2d center = start + left * side * r;
    const double arc_len = r * std::abs(turn);
    const int n = std::max(2, static_cast<int>(std::ceil(arc_len / (spacing * 0.1))));
    const Eigen::Vector2d rel0 = start - center;
    for (int k = 1; k <= n; ++k) {
      const double ang = turn * k / n;
      const Eigen::Vector2d rel(std::cos(ang) * rel0.x() - std::sin(ang) * rel0.y(),
                                std::sin(ang) * rel0.x() + std::cos(ang) * rel0.y());
      emit_line(center + rel);
    }
  }
  emit_line(corners.back());
  if ((out.back() - corners.back()).norm() > 1e-6) {
    out.push_back(corners.back());
  }
  return out;
}

std::vector<Eigen::Vector2d> offset_polyline(const std::vector<Eigen::Vector2d>& pts,
                                             const std::vector<double>& offset) {
  std::vector<Eigen::Vector2d> out(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1;
    const std::size_t b = std::min(pts.size() - 1, i + 1);
    const Eigen::Vector2d t = (pts[b] - pts[a]).normalized();
    const Eigen::Vector2d right(t.y(), -t.x());
    out[i] = pts[i] + right * offset[i];
  }
  return out;
}

std::vector<Eigen::Vector2d> resample_polyline(const std::vector<Eigen::Vector2d>& pts, double spacing) {
  std::vector<Eigen::Vector2d> out{pts.front()};
  double carry = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const Eigen::Vector2d d = pts[i] - pts[i - 1];
    const double len = d.norm();
    double t = spacing - carry;
    while (t <= len) {
      out.push_back(pts[i - 1] + d * (t / len));
      t += spacing;
    }
    carry = len - (t - spacing);
  }
  return out;
}

std::vector<double> polyline_arclength(const std::vector<Eigen::Vector2d>& pts) {
  std::vector<double> s(pts.size(), 0.0);
  for (std::size_t i = 1; i < pts.size(); ++i) {
    s[i] = s[i - 1] + (pts[i] - pts[i - 1]).norm();
  }
  return s;
}

PathCurve::PathCurve(const std::vector<Eigen::Vector2d>& pts, double sigma) {
  if (pts.size() < 8) {
    throw std::runtime_error("path too short");
  }
  // Gaussian smoothing by index (points are evenly spaced) turns arc/line joints into clothoid-
  // like curvature ramps, as a driver turning the wheel would.
  const double spacing = polyline_arclength(pts).back() / static_cast<double>(pts.size() - 1);
  const double sig = std::max(sigma / spacing, 1e-3);
  const int half = static_cast<int>(std::ceil(3.0 * sig));
  std::vector<double> w(static_cast<std::size_t>(2 * half + 1));
  for (int k = -half; k <= half; ++k) {
    w[static_cast<std::size_t>(k + half)] = std::exp(-0.5 * k * k / (sig * sig));
  }
  const int n = static_cast<int>(pts.size());
  ctrl_.resize(pts.size());
  for (int i = 0; i < n; ++i) {
    Eigen::Vector2d acc = Eigen::Vector2d::Zero();
    double ws = 0.0;
    for (int k = -half; k <= half; ++k) {
      // Mirror about the ends so the path keeps its end direction.
      int j = i + k;
      Eigen::Vector2d p;
      if (j < 0) {
        p = 2.0 * pts[0] - pts[static_cast<std::size_t>(std::min(-j, n - 1))];
      } else if (j >= n) {
        p = 2.0 * pts[static_cast<std::size_t>(n - 1)] -
            pts[static_cast<std::size_t>(std::max(2 * (n - 1) - j, 0))];
      } else {
        p = pts[static_cast<std::size_t>(j)];
      }
      acc += w[static_cast<std::size_t>(k + half)] * p;
      ws += w[static_cast<std::size_t>(k + half)];
    }
    ctrl_[static_cast<std::size_t>(i)] = acc / ws;
  }
  // Arc-length table over the valid parameter range [1, n-2].
  const int steps = 16;
  const double u_end = static_cast<double>(n - 2);
  double s = 0.0;
  Eigen::Vector2d prev;
  eval(1.0, &prev, nullptr, nullptr);
  u_table_.push_back(1.0);
  s_table_.push_back(0.0);
  for (int k = 1; k <= (n - 3) * steps; ++k) {
    const double u = std::min(1.0 + static_cast<double>(k) / steps, u_end);
    Eigen::Vector2d p;
    eval(u, &p, nullptr, nullptr);
    s += (p - prev).norm();
    prev = p;
    u_table_.push_back(u);
    s_table_.push_back(s);
  }
}

void PathCurve::eval(double u, Eigen::Vector2d* p, Eigen::Vector2d* d1, Eigen::Vector2d* d2) const {
  const int n = static_cast<int>(ctrl_.size());
  int k = static_cast<int>(std::floor(u));
  k = std::clamp(k, 1, n - 3);
  const double t = u - k;
  const Eigen::Vector2d& c0 = ctrl_[static_cast<std::size_t>(k - 1)];
  const Eigen::Vector2d& c1 = ctrl_[static_cast<std::size_t>(k)];
  const Eigen::Vector2d& c2 = ctrl_[static_cast<std::size_t>(k + 1)];
  const Eigen::Vector2d& c3 = ctrl_[static_cast<std::size_t>(k + 2)];
  const double it = 1.0 - t;
  if (p != nullptr) {
    *p = (it * it * it * c0 + (3 * t * t * t - 6 * t * t + 4) * c1 +
          (-3 * t * t * t + 3 * t * t + 3 * t + 1) * c2 + t * t * t * c3) /
         6.0;
  }
  if (d1 != nullptr) {
    *d1 = (-it * it * c0 + (3 * t * t - 4 * t) * c1 + (-3 * t * t + 2 * t + 1) * c2 + t * t * c3) /
          2.0;
  }
  if (d2 != nullptr) {
    *d2 = it * c0 + (3 * t - 2) * c1 + (1 - 3 * t) * c2 + t * c3;
  }
}

double PathCurve::param_at(double s) const {
  s = std::clamp(s, 0.0, s_table_.back());
  const auto it = std::upper_bound(s_table_.begin(), s_table_.end(), s);
  const std::size_t hi = std::min<std::size_t>(
      static_cast<std::size_t>(it - s_table_.begin()), s_table_.size() - 1);
  const std::size_t lo = hi == 0 ? 0 : hi - 1;
  const double span = s_table_[hi] - s_table_[lo];
  const double f = span > 1e-12 ? (s - s_table_[lo]) / span : 0.0;
  return u_table_[lo] + f * (u_table_[hi] - u_table_[lo]);
}

Eigen::Vector2d PathCurve::position(double s) const {
  Eigen::Vector2d p;
  eval(param_at(s), &p, nullptr, nullptr);
  return p;
}

double PathCurve::heading(double s) const {
  Eigen::Vector2d d;
  eval(param_at(s), nullptr, &d, nullptr);
  return std::atan2(d.y(), d.x());
}

double PathCurve::curvature(double s) const {
  Eigen::Vector2d d;
  Eigen::Vector2d dd;
  eval(param_at(s), nullptr, &d, &dd);
  const double n = d.norm();
  return (d.x() * dd.y() - d.y() * dd.x()) / std::max(n * n * n, 1e-12);
}

}  // namespace liod::sim
