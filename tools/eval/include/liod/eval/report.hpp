#pragma once
// What liod-eval prints: a table for people, one JSON object for scripts, with the same figures.

#include <nlohmann/json.hpp>
#include <string>

#include "liod/eval/evaluate.hpp"

namespace liod::eval {

std::string format_table(const EvalResult& result);

/// Keys: ate.rmse_m, ate.rot_rmse_deg, rpe.trans_rmse_m, kitti.translational_pct,
/// kitti.rotational_deg_per_100m, poses_associated, length_m, distance.error_pct, duration_s, alignment.mode, ...
/// A figure that could not be computed is null, never 0. Keys keep the order of the table.
nlohmann::ordered_json to_json(const EvalResult& result);

}  // namespace liod::eval
