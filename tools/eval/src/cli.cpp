#include "liod/eval/cli.hpp"

#include <CLI/CLI.hpp>
#include <exception>
#include <filesystem>
#include <ostream>
#include <string>

#include "liod/eval/evaluate.hpp"
#include "liod/eval/io.hpp"
#include "liod/eval/oxts.hpp"
#include "liod/eval/plot.hpp"
#include "liod/eval/report.hpp"

namespace liod::eval {
namespace {

struct CliArgs {
  std::string gt;
  std::string est;
  std::string format = "auto";
  std::string gt_times;
  std::string est_times;
  std::string align = "se3";
  std::size_t align_first = 0;
  double max_dt = 0.02;
  std::string interpolate = "auto";
  double max_gap = 0.1;
  double t_offset = 0.0;
  double delta = 1.0;
  std::string delta_unit = "s";
  std::size_t kitti_step = 10;
  std::string plot;
  std::string pairs;
  std::string plot_plane = "auto";
  std::string up = "auto";
  bool json = false;
};

Trajectory load(const std::string& path, Format format, const std::string& times_path) {
  if (is_oxts_dir(path)) return read_oxts(path);
  if (std::filesystem::is_directory(path)) {
    throw InputError(path + ": a folder without oxts/timestamps.txt (give a trajectory file or a KITTI raw drive)");
  }
  Trajectory t = read_trajectory(path, format);
  if (!times_path.empty()) {
    std::vector<double> stamps = read_times(times_path);
    if (stamps.size() != t.size()) {
      throw InputError(times_path + ": " + std::to_string(stamps.size()) + " timestamps for " +
                       std::to_string(t.size()) + " poses in " + path);
    }
    t.stamps = std::move(stamps);
  }
  return t;
}

// The ground truth frame's vertical: liod's and TUM's worlds are z-up, KITTI's poses live in the
// first left camera's frame, y down.
Eigen::Vector3d up_axis(const std::string& text, Format format, const std::string& gt_path) {
  if (text == "auto") {
    if (is_oxts_dir(gt_path)) return Eigen::Vector3d::UnitZ();  // the devkit's OXTS poses: z up
    const Format f = format == Format::Auto ? detect_format(gt_path) : format;
    return f == Format::Kitti ? Eigen::Vector3d(0, -1, 0) : Eigen::Vector3d::UnitZ();
  }
  const double sign = text.front() == '-' ? -1.0 : 1.0;
  const char axis = text.back();
  return sign * Eigen::Vector3d::Unit(axis - 'x');
}

}  // namespace

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"liod-eval: trajectory accuracy (ATE, RPE as evo computes them, and the KITTI odometry metric)",
               "liod-eval"};
  CliArgs a;
  app.add_option("--gt", a.gt, "Ground-truth trajectory (TUM or KITTI), or a KITTI raw drive's OXTS (DRIVE or DRIVE/oxts)")->required();
  app.add_option("--est", a.est, "Estimated trajectory (TUM or KITTI)")->required();
  app.add_option("--format", a.format, "auto|tum|kitti (auto: 8 numbers a line = TUM, 12 = KITTI)")
      ->check(CLI::IsMember({"auto", "tum", "kitti"}));
  app.add_option("--gt-times", a.gt_times, "KITTI times.txt for the ground truth (pairs by time, not index)");
  app.add_option("--est-times", a.est_times, "KITTI times.txt for the estimate");
  app.add_option("--align", a.align, "none|se3|sim3 (Umeyama 1991)")->check(CLI::IsMember({"none", "se3", "sim3"}));
  app.add_option("--align-first", a.align_first,
                 "Align on the first N pairs only (1: first pose coincides; 0: all pairs)");
  app.add_option("--max-dt", a.max_dt, "Nearest-stamp pairing: largest time difference, s")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--interpolate", a.interpolate,
                 "auto|on|off: interpolate the ground truth at estimate stamps (auto: when it is denser)")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  app.add_option("--max-gap", a.max_gap, "Interpolation: largest ground-truth interval to bridge, s")
      ->check(CLI::PositiveNumber);
  app.add_option("--t-offset", a.t_offset, "Seconds added to the estimate's stamps before pairing");
  auto* delta_opt = app.add_option("--delta", a.delta, "RPE spacing of the pose pairs")->check(CLI::PositiveNumber);
  auto* unit_opt = app.add_option("--delta-unit", a.delta_unit, "m|s|frames (m: ground-truth path length)")
                       ->check(CLI::IsMember({"m", "s", "frames"}));
  app.add_option("--kitti-step", a.kitti_step, "KITTI metric: frames between segment starts (devkit: 10)")
      ->check(CLI::PositiveNumber);
  app.add_option("--plot", a.plot,
                 "Write a PNG (matplotlib, via liod-eval-plot): top views of both trajectories and of the "
                 "estimate coloured by its ATE, ATE against distance");
  app.add_option("--pairs", a.pairs,
                 "Write the associated pairs as CSV: ground truth, aligned estimate, ATE (liod-eval-plot's input)");
  app.add_option("--plot-plane", a.plot_plane, "auto|xy|xz|yz (auto: the plane the ground truth spreads in)")
      ->check(CLI::IsMember({"auto", "xy", "xz", "yz"}));
  app.add_option("--up", a.up,
                 "auto|x|y|z|-x|-y|-z: the ground truth's vertical, for the ATE's along/across/up split "
                 "(auto: z, or -y for KITTI files)")
      ->check(CLI::IsMember({"auto", "x", "y", "z", "-x", "-y", "-z"}));
  app.add_flag("--json", a.json, "Print one JSON object instead of the table");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e, out, err);
  }

  try {
    const Format format = parse_format(a.format);
    const Trajectory gt = load(a.gt, format, a.gt_times);
    const Trajectory est = load(a.est, format, a.est_times);

    EvalOptions o;
    o.association.max_dt = a.max_dt;
    o.association.max_gap = a.max_gap;
    o.association.est_time_offset = a.t_offset;
    o.association.interpolation = parse_interpolation(a.interpolate);
    o.alignment.mode = parse_align_mode(a.align);
    o.alignment.first_n = a.align_first;
    o.rpe.delta = a.delta;
    o.rpe.unit = parse_delta_unit(a.delta_unit);
    o.kitti.step = a.kitti_step;
    o.up = up_axis(a.up, format, a.gt);
    const bool stamped = gt.has_stamps() && est.has_stamps();
    std::string rpe_note;
    if (!stamped && unit_opt->count() == 0) {
      // Without time, the default "1 s" has no meaning; fall back to evo's default of 1 frame.
      o.rpe.unit = DeltaUnit::Frames;
      if (delta_opt->count() == 0) o.rpe.delta = 1.0;
      rpe_note = "no timestamps: RPE spacing in frames (give --delta-unit to choose)";
    }

    EvalResult result = evaluate(gt, est, o);
    if (!rpe_note.empty()) result.notes.insert(result.notes.begin(), rpe_note);
    if (!a.pairs.empty()) write_pairs(a.pairs, result);
    if (!a.plot.empty()) {
      PlotOptions po;
      po.plane = a.plot_plane;
      write_plot(a.plot, result, po);
    }
    if (a.json) {
      out << to_json(result).dump(2) << '\n';
    } else {
      out << format_table(result);
      if (!a.pairs.empty()) out << "pairs          " << a.pairs << '\n';
      if (!a.plot.empty()) out << "plot           " << a.plot << '\n';
    }
    return 0;
  } catch (const std::exception& e) {
    err << "liod-eval: error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace liod::eval
