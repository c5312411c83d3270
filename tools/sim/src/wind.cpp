// Wind in porous vegetation (liod-sim --wind). A crown, bush or hedge moves as a whole: it leans
// downwind as the gusts rise and fall (one slow gust cycle shared by the whole world, so the lean
// is coherent, as it is under a real gust) and sways about the lean in three modes of its own. Tree
// crowns sway at 0.3-1 Hz by up to about a decimetre, bushes and hedges faster and by a few
// centimetres (a tree's first bending mode lies at 0.2-1 Hz; shrubs are stiffer). Only porous
// primitives move: trunks, poles and buildings stand still.

#include <cmath>
#include <numbers>

#include "liod/sim/world.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kWindStream = 0x77696E64ULL;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

Sway draw_sway(Rng& rng, double amplitude, double f_lo, double f_hi) {
  Sway s;
  s.amplitude = static_cast<float>(amplitude);
  for (auto& m : s.modes) {
    m.frequency = static_cast<float>(rng.uniform(f_lo, f_hi));
    m.phase_x = static_cast<float>(rng.uniform(0.0, kTwoPi));
    m.phase_y = static_cast<float>(rng.uniform(0.0, kTwoPi));
  }
  return s;
}
}  // namespace

void World::enable_wind(std::uint64_t seed) {
  wind_ = true;
  wind_seed_ = seed;
}

void World::build_sway() {
  sway_.clear();
  if (!wind_) {
    return;
  }
  Rng rng(derive_seed(wind_seed_, kWindStream));
  const double heading = rng.uniform(0.0, kTwoPi);
  wind_dir_ = Eigen::Vector2d(std::cos(heading), std::sin(heading));
  gust_frequency_ = rng.uniform(0.03, 0.08);
  gust_phase_ = rng.uniform(0.0, kTwoPi);
  sway_.assign(primitive_count(), Sway{});
  std::uint32_t id = 0;
  for (const auto& b : boxes) {
    // Porous boxes are hedges (a few cm) and chain-link fences (barely move).
    Rng own(derive_seed(wind_seed_, kWindStream, id + 1));
    if (b.look.kind == SurfaceKind::Porous) {
      sway_[id] = draw_sway(own, b.look.extinction > 5.0F ? 0.01 : own.uniform(0.02, 0.04), 0.8, 2.0);
    }
    ++id;
  }
  id += static_cast<std::uint32_t>(cylinders.size());
  for (const auto& e : ellipsoids) {
    Rng own(derive_seed(wind_seed_, kWindStream, id + 1));
    const bool crown = e.radii.z() >= 1.2;
    sway_[id] = crown ? draw_sway(own, 0.03 + 0.03 * e.radii.z(), 0.3, 1.0)
                      : draw_sway(own, own.uniform(0.02, 0.04), 0.8, 2.0);
    ++id;
  }
}

Eigen::Vector2d World::sway(std::uint32_t id, double t) const {
  if (sway_.empty() || sway_[id].amplitude == 0.0F) {
    return Eigen::Vector2d::Zero();
  }
  const Sway& s = sway_[id];
  const double lean = 0.5 + 0.5 * std::sin(kTwoPi * gust_frequency_ * t + gust_phase_);
  Eigen::Vector2d d = lean * wind_dir_;
  for (const auto& m : s.modes) {
    const double w = kTwoPi * static_cast<double>(m.frequency) * t;
    d.x() += std::sin(w + static_cast<double>(m.phase_x)) / 3.0;
    d.y() += std::sin(w + static_cast<double>(m.phase_y)) / 3.0;
  }
  return static_cast<double>(s.amplitude) * d;
}

const Eigen::Vector2d& World::sway_at(std::uint32_t id, RayContext& ctx) const {
  // The rays of one firing span 45 us, in which a crown moves well under a millimetre.
  if (!(std::abs(ctx.sway_time_[id] - ctx.time_) < 2e-4)) {
    ctx.sway_time_[id] = ctx.time_;
    ctx.sway_[id] = sway(id, ctx.time_);
  }
  return ctx.sway_[id];
}

}  // namespace liod::sim
