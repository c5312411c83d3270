#include "liod/sim/drive.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "liod/sim/angles.hpp"
#include "liod/sim/rng.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kDriveStream = 0x6472697665ULL;
constexpr std::uint64_t kVibrationStream = 0x7669627261ULL;
constexpr double kKnot = 0.01;    // s between spline control points
constexpr double kStep = 0.001;   // s, driver and suspension integration step
constexpr double kProfileDs = 0.5;

/// One wheel track's road profile: a sum of sinusoids whose amplitudes follow the ISO 8608
/// spectrum G(n) = G0 (n / 0.1)^-2 over wavelengths of 0.3 to 50 m.
class RoadProfile {
 public:
  RoadProfile(double g0, Rng& rng) {
    const int bands = 48;
    const double n_lo = 0.02;
    const double n_hi = 3.0;
    const double ratio = std::pow(n_hi / n_lo, 1.0 / bands);
    for (int i = 0; i < bands; ++i) {
      const double n = n_lo * std::pow(ratio, i + rng.uniform());
      const double dn = n * (ratio - 1.0);
      const double g = g0 * std::pow(n / 0.1, -2.0);
      k_.push_back(2.0 * std::numbers::pi * n);
      a_.push_back(std::sqrt(2.0 * g * dn));
      p_.push_back(rng.uniform(0.0, 2.0 * std::numbers::pi));
    }
  }
  double height(double s) const {
    double h = 0.0;
    for (std::size_t i = 0; i < k_.size(); ++i) {
      h += a_[i] * std::sin(k_[i] * s + p_[i]);
    }
    return h;
  }

 private:
  std::vector<double> k_, a_, p_;
};

/// Second-order body mode driven by its quasi-static target.
struct BodyMode {
  double omega = 0.0;
  double zeta = 0.0;
  double x = 0.0;
  double xd = 0.0;
  void step(double target, double target_rate, double dt) {
    const double acc = -2.0 * zeta * omega * (xd - target_rate) - omega * omega * (x - target);
    xd += acc * dt;
    x += xd * dt;
  }
};

std::vector<double> speed_profile(const DrivePlan& plan, const PathCurve& path,
                                  const VehicleParams& veh) {
  const auto n = static_cast<std::size_t>(path.length() / kProfileDs) + 1;
  const std::vector<double> plan_s = polyline_arclength(plan.points);
  std::vector<double> v(n);
  std::size_t j = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) * kProfileDs;
    while (j + 1 < plan_s.size() && plan_s[j + 1] < s) {
      ++j;
    }
    const double cap = plan.speed_cap[std::min(j, plan.speed_cap.size() - 1)];
    // Look at the tightest curvature within a car length so corners are entered slowly enough.
    double kmax = 0.0;
    for (double ds = -2.0; ds <= 2.0; ds += 1.0) {
      kmax = std::max(kmax, std::abs(path.curvature(s + ds)));
    }
    const double v_lat = kmax > 1e-6 ? std::sqrt(veh.max_lateral_accel * 0.92 / kmax) : 1e9;
    v[i] = std::min({cap, v_lat, plan.cruise_speed});
  }
  for (std::size_t i = 1; i < n; ++i) {
    v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2.0 * veh.max_accel * 0.8 * kProfileDs));
  }
  for (std::size_t i = n - 1; i-- > 0;) {
    v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2.0 * veh.max_decel * 0.8 * kProfileDs));
  }
  return v;
}

double interp(const std::vector<double>& v, double s) {
  const double x = std::clamp(s / kProfileDs, 0.0, static_cast<double>(v.size() - 1));
  const auto i = std::min(static_cast<std::size_t>(x), v.size() - 2);
  const double f = x - static_cast<double>(i);
  return (1 - f) * v[i] + f * v[i + 1];
}
}  // namespace

Trajectory generate_drive(const DrivePlan& plan, const PathCurve& path, const Terrain& terrain,
                          const VehicleParams& veh, double duration, std::uint64_t seed,
                          DriveStats* stats) {
  Rng rng(derive_seed(seed, kDriveStream));
  const std::vector<double> profile = speed_profile(plan, path, veh);
  RoadProfile left(veh.roughness, rng);
  RoadProfile right(veh.roughness, rng);

  BodyMode heave{2 * std::numbers::pi * veh.body_heave_hz, veh.body_damping};
  BodyMode pitch{2 * std::numbers::pi * veh.body_pitch_hz, veh.body_damping};
  BodyMode roll{2 * std::numbers::pi * veh.body_roll_hz, veh.body_damping};

  const double t_begin = -4 * kKnot;
  const double t_end = duration + 1.0;
  const double s_begin = 4.0;  // leaves room behind the start for the spline's support
  const bool rolling = plan.static_start_s <= 0.0;
  double s = s_begin;
  double v = rolling ? interp(profile, s) : 0.0;
  double a = 0.0;
  std::size_t next_stop = 0;
  double dwell_until = rolling ? -1e9 : plan.static_start_s;
  DriveStats st;

  const double L = veh.wheelbase;
  const double W = veh.track;
  auto road_inputs = [&](double sv, double& h, double& p, double& r) {
    const double fl = left.height(sv + L / 2);
    const double fr = right.height(sv + L / 2);
    const double rl = left.height(sv - L / 2);
    const double rr = right.height(sv - L / 2);
    h = 0.25 * (fl + fr + rl + rr);
    p = (0.5 * (rl + rr) - 0.5 * (fl + fr)) / L;
    r = (0.5 * (fl + rl) - 0.5 * (fr + rr)) / W;
  };
  double prev_h = 0.0;
  double prev_p = 0.0;
  double prev_r = 0.0;
  road_inputs(s, prev_h, prev_p, prev_r);
  heave.x = prev_h;
  pitch.x = prev_p;
  roll.x = prev_r;

  std::vector<Sample6> samples;
  const auto knots = static_cast<std::size_t>(std::ceil((t_end - t_begin) / kKnot)) + 1;
  samples.reserve(knots);
  const int sub = static_cast<int>(std::lround(kKnot / kStep));
  double yaw_prev = path.heading(s);
  double t = t_begin;
  for (std::size_t k = 0; k < knots; ++k) {
    // Record the knot sample from the current state.
    const Eigen::Vector2d c = path.position(s);
    double yaw = path.heading(s);
    yaw = yaw_prev + std::remainder(yaw - yaw_prev, 2.0 * std::numbers::pi);
    yaw_prev = yaw;
    const Eigen::Vector2d fwd(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d lft(-fwd.y(), fwd.x());
    auto ground = [&](double df, double dl) {
      const Eigen::Vector2d q = c + df * fwd + dl * lft;
      return terrain.height(q.x(), q.y());
    };
    const double hfl = ground(L / 2, W / 2);
    const double hfr = ground(L / 2, -W / 2);
    const double hrl = ground(-L / 2, W / 2);
    const double hrr = ground(-L / 2, -W / 2);
    const double z = 0.25 * (hfl + hfr + hrl + hrr) + veh.imu_height + heave.x;
    const double terrain_pitch = std::atan2(0.5 * (hrl + hrr) - 0.5 * (hfl + hfr), L);
    const double terrain_roll = std::atan2(0.5 * (hfl + hrl) - 0.5 * (hfr + hrr), W);
    samples.push_back({c.x(), c.y(), z, terrain_roll + roll.x, terrain_pitch + pitch.x, yaw});

    // Advance driver and suspension to the next knot.
    for (int i = 0; i < sub; ++i) {
      double v_ref = interp(profile, s + 0.5 + v * 0.6);
      if (next_stop < plan.stops.size()) {
        const double gap = plan.stops[next_stop].s - s;
        v_ref = std::min(v_ref, std::sqrt(2.0 * 1.3 * std::max(0.0, gap - 0.3)));
        if (gap < 2.5 && v < 0.03 && dwell_until < t) {
          dwell_until = t + plan.stops[next_stop].duration;
          ++next_stop;
          ++st.stops;
        }
      }
      double a_des = std::clamp(1.5 * (v_ref - v), -3.5, veh.max_accel);
      if (t < dwell_until) {
        a_des = 0.0;
        v = 0.0;
        a = 0.0;
      }
      a += std::clamp(a_des - a, -veh.max_jerk * 1.5 * kStep, veh.max_jerk * kStep);
      v += a * kStep;
      if (v <= 0.0) {
        v = 0.0;
        a = std::max(a, 0.0);
      }
      s = std::min(s + v * kStep, path.length() - 2.0);
      t += kStep;

      const double kappa = path.curvature(s);
      const double a_lat = v * v * kappa;
      double rh = 0.0;
      double rp = 0.0;
      double rr = 0.0;
      road_inputs(s, rh, rp, rr);
      // Load transfer: the body leans out of turns (right when turning left: roll > 0 lifts the
      // left side) and dives when braking (pitch > 0 is nose down).
      rr += veh.roll_per_lat_accel * kDeg * a_lat;
      rp -= veh.pitch_per_long_accel * kDeg * a;
      heave.step(rh, (rh - prev_h) / kStep, kStep);
      pitch.step(rp, (rp - prev_p) / kStep, kStep);
      roll.step(rr, (rr - prev_r) / kStep, kStep);
      prev_h = rh;
      prev_p = rp;
      prev_r = rr;
      if (t >= 0.0 && t <= duration) {
        st.top_speed = std::max(st.top_speed, v);
        st.peak_lateral_accel = std::max(st.peak_lateral_accel, std::abs(a_lat));
        st.peak_long_accel = std::max(st.peak_long_accel, a);
        st.peak_decel = std::max(st.peak_decel, -a);
      }
    }
    if (t <= duration) {
      st.distance = s - s_begin;
    }
  }

  // Engine and tyre vibration: small, fast, present even at rest.
  std::vector<Sinusoid> vib;
  const double wz = 2 * std::numbers::pi * rng.uniform(22.0, 28.0);
  vib.push_back({2, 0.06 / (wz * wz), wz / (2 * std::numbers::pi), rng.uniform(0, 6.28)});
  const double wz2 = 2 * std::numbers::pi * rng.uniform(11.0, 15.0);
  vib.push_back({2, 0.08 / (wz2 * wz2), wz2 / (2 * std::numbers::pi), rng.uniform(0, 6.28)});
  for (int ch = 3; ch <= 5; ++ch) {
    const double w = 2 * std::numbers::pi * rng.uniform(14.0, 21.0);
    vib.push_back({ch, 0.004 / w, w / (2 * std::numbers::pi), rng.uniform(0, 6.28)});
  }
  if (veh.road_vibration > 0.0) {
    // Each mode a narrow band: three sinusoids within +-10 % of its frequency whose beats make the
    // shaking come and go; its RMS is that of one sinusoid of the band's amplitude.
    Rng vr(derive_seed(seed, kVibrationStream));
    auto band = [&](int channel, double hz, double amplitude) {
      for (int k = 0; k < 3; ++k) {
        vib.push_back({channel, veh.road_vibration * amplitude / std::sqrt(3.0), hz * vr.uniform(0.9, 1.1),
                       vr.uniform(0.0, 2.0 * std::numbers::pi)});
      }
    };
    band(2, 3.0, 0.004);    // body bounce
    band(2, 11.0, 0.0004);  // wheel hop, through the suspension
    band(4, 9.0, 0.0008);   // pitch shake
    band(3, 11.0, 0.0004);  // roll shake, the wheels of an axle hopping out of phase
  }
  if (stats != nullptr) {
    *stats = st;
  }
  return Trajectory(t_begin, kKnot, std::move(samples), std::move(vib));
}

}  // namespace liod::sim
