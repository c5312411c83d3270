#include "liod/eval/evaluate.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include "liod/eval/io.hpp"

namespace liod::eval {

EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options) {
  EvalResult r;
  r.gt_name = gt.name;
  r.est_name = est.name;
  r.gt_poses = gt.size();
  r.est_poses = est.size();
  r.association_options = options.association;
  r.association = associate(gt, est, options.association);
  const Association& a = r.association;
  if (a.est.size() < est.size()) {
    r.notes.push_back(std::to_string(est.size() - a.est.size()) + " of " + std::to_string(est.size()) +
                      " estimate poses found no ground truth and are not evaluated");
  }

  r.alignment = align(a.gt, a.est, options.alignment);
  r.est_aligned = apply_similarity(r.alignment.transform, a.est);
  if (options.alignment.mode != AlignMode::None && r.alignment.transform.degenerate && r.alignment.pairs_used > 1) {
    r.notes.emplace_back(
        "alignment is degenerate: the aligned ground-truth positions are (nearly) collinear, so the roll "
        "about that line is arbitrary; translation errors hold, rotation ATE does not");
  }

  r.ate = compute_ate(a.gt, r.est_aligned);
  r.ate_split = compute_ate_split(a.gt, r.est_aligned, options.up);

  RpeOptions rpe = options.rpe;
  if (!a.by_time && rpe.unit == DeltaUnit::Seconds) {
    throw InputError("--delta-unit s needs timestamps; KITTI files without --gt-times/--est-times have none "
                     "(use --delta-unit frames or m)");
  }
  r.rpe = compute_rpe(a.stamps, a.gt, r.est_aligned, rpe);
  if (!r.rpe) {
    std::ostringstream msg;
    msg << "RPE not computed: no pair of poses " << rpe.delta << ' ' << to_string(rpe.unit) << " apart";
    r.notes.push_back(msg.str());
  }

  r.kitti = kitti_odometry_error(a.gt, r.est_aligned, options.kitti);
  r.length_m = r.kitti.gt_length_m;
  r.distance = compute_distance_travelled(a.gt, a.est);
  if (!r.kitti.translational_pct) {
    std::ostringstream msg;
    msg << std::fixed << std::setprecision(1) << "KITTI metric not computed: the ground-truth path is "
        << r.length_m << " m, shorter than the shortest segment length "
        << (options.kitti.lengths_m.empty()
                ? 0.0
                : *std::min_element(options.kitti.lengths_m.begin(), options.kitti.lengths_m.end()))
        << " m";
    r.notes.push_back(msg.str());
  }
  if (a.by_time) r.duration_s = a.stamps.back() - a.stamps.front();
  return r;
}

}  // namespace liod::eval
