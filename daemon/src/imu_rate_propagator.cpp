#include "liod/daemon/imu_rate_propagator.hpp"

#include "liod/imu_trajectory.hpp"

namespace liod {
namespace {
// Enough for the longest a scan update can lag its samples (scan ring + IMU wait) at 1 kHz.
constexpr std::size_t kMaxHistory = 4096;

// The measurement noise only shapes a preintegration's covariance, which is not used here.
ImuPreintegration preintegration_for(const NavState& s) { return ImuPreintegration(s.gyro_bias, s.accel_bias, ImuNoise{}); }
}  // namespace

void ImuRatePropagator::set_anchor(const ScanAnchor& anchor) {
  anchor_ = anchor;
  const double t = anchor.state.time;
  while (history_.size() > 1 && history_[1].time <= t) history_.pop_front();
  state_ = anchor.state;
  if (history_.empty() || history_.back().time <= t) {
    last_.time = -1.0;  // the next sample starts the propagation, interpolated back to t
    return;
  }
  // The same intervals as the odometry's own propagation (interpolated at the anchor's time).
  ImuPreintegration p = preintegration_for(state_);
  for (const auto& iv : imu_intervals(history_, t, history_.back().time)) p.integrate(iv.gyro, iv.accel, iv.dt);
  state_ = p.predict(anchor.state, anchor.gravity);
  state_.time = history_.back().time;
  last_ = history_.back();
}

void ImuRatePropagator::step(const ImuSample& next) {
  ImuSample previous = last_;
  if (previous.time < state_.time) {
    // First sample after the anchor: the measurement at the anchor's time, interpolated between
    // the sample before it (if kept) and this one.
    previous = next;
    if (!history_.empty() && history_.back().time <= state_.time && next.time > history_.back().time) {
      const ImuSample& before = history_.back();
      const double s = (state_.time - before.time) / (next.time - before.time);
      previous.gyro = (1.0 - s) * before.gyro + s * next.gyro;
      previous.accel = (1.0 - s) * before.accel + s * next.accel;
    }
    previous.time = state_.time;
  }
  const double dt = next.time - previous.time;
  if (dt > 1e-9) {
    ImuPreintegration p = preintegration_for(state_);
    p.integrate(0.5 * (previous.gyro + next.gyro), 0.5 * (previous.accel + next.accel), dt);
    const double time = next.time;
    state_ = p.predict(state_, anchor_->gravity);
    state_.time = time;
  }
  last_ = next;
}

std::optional<NavState> ImuRatePropagator::add(const ImuSample& sample) {
  if (!history_.empty() && sample.time <= history_.back().time) return std::nullopt;
  std::optional<NavState> out;
  if (anchor_ && sample.time > state_.time) {
    step(sample);
    out = state_;
  }
  history_.push_back(sample);
  if (history_.size() > kMaxHistory) history_.pop_front();
  return out;
}

void AnchorExchange::publish(const ScanAnchor& anchor) {
  std::lock_guard lock(mutex_);
  anchor_ = anchor;
  generation_.fetch_add(1, std::memory_order_release);
}

bool AnchorExchange::take(ScanAnchor& out) {
  if (generation_.load(std::memory_order_acquire) == taken_) return false;
  std::lock_guard lock(mutex_);
  out = anchor_;
  taken_ = generation_.load(std::memory_order_relaxed);
  return true;
}

}  // namespace liod
