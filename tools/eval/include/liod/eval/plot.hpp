#pragma once
// liod-eval --plot: the figures are drawn by liod-eval-plot (a Python script with matplotlib,
// installed beside liod-eval) from the pairs file liod-eval writes: per associated pair the ground
// truth, the aligned estimate and the ATE. liod-eval-plot's header lists the figures.

#include <iosfwd>
#include <string>

#include "liod/eval/evaluate.hpp"

namespace liod::eval {

/// Column names of the pairs file, in order (liod-eval-plot checks the header against them).
inline constexpr const char* kPairsHeader = "t,distance_m,gt_x,gt_y,gt_z,est_x,est_y,est_z,ate_m,ate_rot_deg";

/// The pairs file: `# key=value` lines (alignment, gt, est), the header, then one CSV row per pair:
/// the pair's stamp (nan when paired by index), the ground truth's path length up to it, the ground
/// truth's and the aligned estimate's positions, and the ATE (m, deg).
void write_pairs(std::ostream& out, const EvalResult& result);
/// Throws InputError naming the path when it cannot be written.
void write_pairs(const std::string& path, const EvalResult& result);

struct PlotOptions {
  /// "xy", "xz", "yz" or "auto" (the two axes along which the ground truth spreads most).
  std::string plane = "auto";
  /// The plot script; empty: liod-eval-plot in the directory of the running executable.
  std::string script;
};

/// The path of liod-eval-plot beside the running executable (/proc/self/exe).
std::string default_plot_script();

/// Writes the pairs to a temporary file, runs the script on it and removes it. Throws
/// std::runtime_error when the script cannot be started or fails (its own message on stderr).
void write_plot(const std::string& png_path, const EvalResult& result, const PlotOptions& options = {});

}  // namespace liod::eval
