#pragma once
// Each front-end unit's own config struct, filled from the front end's configuration: the one
// place that knows which key feeds which unit.

#include "liod/algorithm_config.hpp"
#include "liod/bias_holds.hpp"
#include "liod/curvature_features.hpp"
#include "liod/imu_preintegration.hpp"
#include "liod/iterated_update.hpp"
#include "liod/keyframe_window.hpp"
#include "liod/move_off.hpp"
#include "liod/reinitialization.hpp"
#include "liod/start_up.hpp"

namespace liod {

ImuNoise imu_noise(const ImuConfig& imu);
FeatureParams feature_params(const FrontEndConfig& config);
StartUpConfig start_up_config(const FrontEndConfig& config);
BiasHoldConfig bias_hold_config(const OdometryConfig& odometry);
MoveOffConfig move_off_config(const OdometryConfig& odometry);
UpdateParams update_params(const FrontEndConfig& config);
/// `update`: the update's parameters (update_params), whose post model the window's post map shares.
ReinitializationConfig reinitialization_config(const OdometryConfig& odometry, const StateLimits& limits);
KeyframeWindowConfig keyframe_window_config(const OdometryConfig& odometry, const UpdateParams& update);

}  // namespace liod
