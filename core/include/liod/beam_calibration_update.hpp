#pragma once
// Feeds the beam calibration (beam_calibration.hpp) with a registered scan: each plane point's
// residual against the map at the updated pose, and how it would move with its beam's elevation
// or range. Elevations from the far ground only: there an elevation offset moves a point across
// the surface (along the ray on a wall it hardly does) and the map is densest. Ranges, when
// learned, from every other plane point.

#include "liod/beam_calibration.hpp"
#include "liod/deskew.hpp"
#include "liod/error_state.hpp"
#include "liod/local_map.hpp"
#include "liod/map_correspondence.hpp"

namespace liod {

/// `features` were deskewed into the body frame of `state` (the scan's updated end state).
void update_beam_calibration(BeamCalibration& calibration, const DeskewedFeatures& features, const NavState& state,
                             const Pose& lidar_to_imu, const LocalMap& plane_map,
                             const CorrespondenceParams& correspondence, double lidar_noise_m);

}  // namespace liod
