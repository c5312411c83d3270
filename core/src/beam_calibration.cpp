#include "liod/beam_calibration.hpp"

#include <algorithm>
#include <cmath>

#include "liod/angles.hpp"

namespace liod {

BeamCalibration::BeamCalibration(std::size_t beams, const BeamCalibrationParams& params)
    : params_(params),
      prior_information_(1.0 / std::pow(params.prior_std_deg * kDegToRad, 2)),
      range_prior_information_(1.0 / std::pow(params.range_prior_std_m, 2)),
      beams_(beams) {}

Eigen::Vector3d BeamCalibration::elevation_derivative(const Eigen::Vector3d& point) {
  const double horizontal = std::hypot(point.x(), point.y());
  if (horizontal < 1e-9) return Eigen::Vector3d::Zero();
  // d/de of range * (cos e cos a, cos e sin a, sin e), with range cos e = horizontal, range sin e = z.
  return {-point.z() * point.x() / horizontal, -point.z() * point.y() / horizontal, horizontal};
}

Eigen::Vector3d BeamCalibration::correct(const Eigen::Vector3d& point, std::uint16_t ring) const {
  if (ring >= beams_.size()) return point;
  const Beam& b = beams_[ring];
  Eigen::Vector3d out = point;
  const double range = point.norm();
  if (b.range.offset != 0.0 && range > 1e-9) out += (b.range.offset / range) * point;
  if (b.elevation.offset != 0.0) out += b.elevation.offset * elevation_derivative(out);
  return out;
}

void BeamCalibration::Estimate::add(double jacobian, double residual, double variance) {
  scan_information += jacobian * jacobian / variance;
  scan_gradient += jacobian * residual / variance;
}

double BeamCalibration::Estimate::fold(double forgetting, double prior_information) {
  information = forgetting * information + scan_information;
  gradient = forgetting * gradient + scan_gradient;
  scan_information = scan_gradient = 0.0;
  return offset - (gradient + prior_information * offset) / (information + prior_information);
}

void BeamCalibration::Estimate::move_towards(double target, double step, double limit) {
  const double moved = std::clamp(offset + step * (target - offset), -limit, limit) - offset;
  offset += moved;
  // The sums were measured at the old offset; to first order they now read as at the new one.
  gradient += information * moved;
}

namespace {
bool usable(double jacobian, double residual, double variance) {
  return variance > 0.0 && std::isfinite(jacobian) && std::isfinite(residual);
}
}  // namespace

void BeamCalibration::add_elevation(std::uint16_t ring, double elevation, double jacobian, double residual,
                                    double variance) {
  if (ring >= beams_.size() || !usable(jacobian, residual, variance) || !std::isfinite(elevation)) return;
  Beam& b = beams_[ring];
  b.elevation.add(jacobian, residual, variance);
  b.scan_elevation_sum += elevation;
  b.scan_weight += 1.0;
}

void BeamCalibration::add_range(std::uint16_t ring, double jacobian, double residual, double variance) {
  if (!params_.learn_ranges || ring >= beams_.size() || !usable(jacobian, residual, variance)) return;
  beams_[ring].range.add(jacobian, residual, variance);
}

void BeamCalibration::finish_scan() {
  finish_elevations();
  if (params_.learn_ranges) finish_ranges();
}

void BeamCalibration::finish_elevations() {
  const double f = params_.forgetting;
  std::vector<double> target(beams_.size(), 0.0);
  double elevation_target = 0.0;
  double elevation_squared = 0.0;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Beam& b = beams_[k];
    target[k] = b.elevation.fold(f, prior_information_);
    b.elevation_sum = f * b.elevation_sum + b.scan_elevation_sum;
    b.weight = f * b.weight + b.scan_weight;
    b.scan_elevation_sum = b.scan_weight = 0.0;
    if (b.elevation.information < params_.min_information) continue;
    const double elevation = b.elevation_sum / b.weight;
    elevation_target += elevation * target[k];
    elevation_squared += elevation * elevation;
  }
  if (!(elevation_squared > 0.0)) return;
  const double gauge_slope = elevation_target / elevation_squared;  // the unobservable part, b * elevation
  const double limit = params_.max_offset_deg * kDegToRad;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Beam& b = beams_[k];
    if (b.elevation.information < params_.min_information) continue;
    b.elevation.move_towards(target[k] - gauge_slope * b.elevation_sum / b.weight, params_.step, limit);
  }
}

void BeamCalibration::finish_ranges() {
  std::vector<double> target(beams_.size(), 0.0);
  double common = 0.0;
  int learned = 0;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Estimate& range = beams_[k].range;
    target[k] = range.fold(params_.forgetting, range_prior_information_);
    if (range.information < params_.min_range_information) continue;
    common += target[k];
    ++learned;
  }
  if (learned == 0) return;
  common /= learned;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Estimate& range = beams_[k].range;
    if (range.information < params_.min_range_information) continue;
    range.move_towards(target[k] - common, params_.step, params_.max_range_offset_m);
  }
}

}  // namespace liod
