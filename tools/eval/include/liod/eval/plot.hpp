#pragma once
// liod-eval --plot: top panel the trajectories seen from above (ground truth and aligned estimate,
// equal axis scale, start marked), bottom panel the translational ATE against distance travelled.

#include <string>

#include "liod/eval/canvas.hpp"
#include "liod/eval/evaluate.hpp"

namespace liod::eval {

struct PlotOptions {
  /// "xy", "xz", "yz" or "auto": the two axes along which the ground truth spreads most (KITTI's
  /// camera frame drives in x-z, a body-frame trajectory in x-y).
  std::string plane = "auto";
  int width = 1000;
  int height = 1100;
};

Canvas render_plot(const EvalResult& result, const PlotOptions& options = {});
void write_plot(const std::string& path, const EvalResult& result, const PlotOptions& options = {});

/// Round tick step (1, 2 or 5 times a power of ten) giving about `target` ticks across `range`.
double nice_step(double range, int target);
/// Tick label with as many decimals as the step needs ("-12.5", "300").
std::string tick_label(double value, double step);

}  // namespace liod::eval
