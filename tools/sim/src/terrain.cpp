#include "liod/sim/terrain.hpp"

#include <algorithm>
#include <cmath>

namespace liod::sim {

namespace {
// C1 blend so the vehicle's pitch never jumps where the corridor meets the terrain.
double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
}  // namespace

double Terrain::natural_height(double x, double y) const {
  double h = 0.0;
  for (const auto& w : waves) {
    h += w.amplitude * std::sin(w.wave_vector.x() * x + w.wave_vector.y() * y + w.phase);
  }
  for (const auto& hill : hills) {
    const double dx = x - hill.center.x();
    const double dy = y - hill.center.y();
    h += hill.height * std::exp(-(dx * dx + dy * dy) / (2.0 * hill.sigma * hill.sigma));
  }
  return h;
}

double Terrain::corridor_plane(const GradedCorridor& c, double x, double y) {
  const Eigen::Vector2d axis = (c.b - c.a).normalized();
  const double along = axis.dot(Eigen::Vector2d(x, y) - c.a);
  return c.z_at_a + c.grade * along;
}

double Terrain::height(double x, double y) const {
  double h = natural_height(x, y);
  for (const auto& c : corridors) {
    const Eigen::Vector2d ab = c.b - c.a;
    const double len = ab.norm();
    const Eigen::Vector2d axis = ab / len;
    const Eigen::Vector2d ap = Eigen::Vector2d(x, y) - c.a;
    const double along = axis.dot(ap);
    const double lateral = std::abs(axis.x() * ap.y() - axis.y() * ap.x());
    const double beyond = std::max({0.0, -along, along - len});
    const double dist = std::max(lateral - c.half_width, 0.0) + beyond;
    const double w = 1.0 - smoothstep(0.0, c.blend, dist);
    if (w > 0.0) {
      h = (1.0 - w) * h + w * corridor_plane(c, x, y);
    }
  }
  return h;
}

}  // namespace liod::sim
