#include "liod/beam_calibration.hpp"

#include <algorithm>
#include <cmath>

#include "liod/angles.hpp"

namespace liod {

BeamElevationCalibration::BeamElevationCalibration(std::size_t beams, const BeamCalibrationParams& params)
    : params_(params),
      prior_information_(1.0 / std::pow(params.prior_std_deg * kDegToRad, 2)),
      beams_(beams) {}

Eigen::Vector3d BeamElevationCalibration::elevation_derivative(const Eigen::Vector3d& point) {
  const double horizontal = std::hypot(point.x(), point.y());
  if (horizontal < 1e-9) return Eigen::Vector3d::Zero();
  // d/de of range * (cos e cos a, cos e sin a, sin e), with range cos e = horizontal, range sin e = z.
  return {-point.z() * point.x() / horizontal, -point.z() * point.y() / horizontal, horizontal};
}

Eigen::Vector3d BeamElevationCalibration::correct(const Eigen::Vector3d& point, std::uint16_t ring) const {
  const double offset = offset_rad(ring);
  if (offset == 0.0) return point;
  return point + offset * elevation_derivative(point);
}

void BeamElevationCalibration::add(std::uint16_t ring, double elevation, double jacobian, double residual,
                                   double variance) {
  if (ring >= beams_.size() || !(variance > 0.0) || !std::isfinite(jacobian) || !std::isfinite(residual) ||
      !std::isfinite(elevation)) {
    return;
  }
  Beam& b = beams_[ring];
  b.scan_information += jacobian * jacobian / variance;
  b.scan_gradient += jacobian * residual / variance;
  b.scan_elevation_sum += elevation;
  b.scan_weight += 1.0;
}

void BeamElevationCalibration::finish_scan() {
  const double f = params_.forgetting;
  std::vector<double> target(beams_.size(), 0.0);
  double elevation_target = 0.0;
  double elevation_squared = 0.0;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Beam& b = beams_[k];
    b.information = f * b.information + b.scan_information;
    b.gradient = f * b.gradient + b.scan_gradient;
    b.elevation_sum = f * b.elevation_sum + b.scan_elevation_sum;
    b.weight = f * b.weight + b.scan_weight;
    b.scan_information = b.scan_gradient = b.scan_elevation_sum = b.scan_weight = 0.0;
    if (b.information < params_.min_information) continue;
    // Gauss-Newton on the forgotten sums, with the prior that the offset is zero.
    target[k] = b.offset - (b.gradient + prior_information_ * b.offset) / (b.information + prior_information_);
    const double elevation = b.elevation_sum / b.weight;
    elevation_target += elevation * target[k];
    elevation_squared += elevation * elevation;
  }
  if (!(elevation_squared > 0.0)) return;
  const double gauge_slope = elevation_target / elevation_squared;  // the unobservable part, b * elevation
  const double limit = params_.max_offset_deg * kDegToRad;
  for (std::size_t k = 0; k < beams_.size(); ++k) {
    Beam& b = beams_[k];
    if (b.information < params_.min_information) continue;
    const double gauged = target[k] - gauge_slope * b.elevation_sum / b.weight;
    const double moved = std::clamp(b.offset + params_.step * (gauged - b.offset), -limit, limit) - b.offset;
    b.offset += moved;
    // The sums were measured at the old offset; to first order they now read as at the new one.
    b.gradient += b.information * moved;
  }
}

}  // namespace liod
