#include "liod/eval/report.hpp"

#include <cstdio>
#include <optional>
#include <sstream>

namespace liod::eval {
namespace {

std::string association_text(const EvalResult& r) {
  const Association& a = r.association;
  if (!a.by_time) return "by index (no timestamps)";
  return a.interpolated ? "by time, ground truth interpolated at estimate stamps" : "by time, nearest stamp";
}

std::string alignment_text(const EvalResult& r) {
  const Alignment& a = r.alignment;
  if (a.options.mode == AlignMode::None) return "none";
  std::string s = to_string(a.options.mode);
  if (a.pairs_used == 1) return s + ", first pose only";
  s += " Umeyama on " + std::string(a.options.first_n == 0 ? "all " : "the first ") + std::to_string(a.pairs_used) +
       " pairs";
  if (a.options.mode == AlignMode::Sim3) {
    char buf[64];
    std::snprintf(buf, sizeof buf, ", scale %.6f", a.transform.scale);
    s += buf;
  }
  return s;
}

void stats_row(std::ostringstream& out, const char* label, const Stats& s, int decimals) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%-18s %11.*f %11.*f %11.*f %11.*f %11.*f %11.*f\n", label, decimals, s.rmse,
                decimals, s.mean, decimals, s.median, decimals, s.std, decimals, s.min, decimals, s.max);
  out << buf;
}

std::string opt(const std::optional<double>& v, int decimals) {
  if (!v) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, *v);
  return buf;
}

using Json = nlohmann::ordered_json;

Json opt_json(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }

void put_stats(Json& j, const std::string& prefix, const std::string& unit, const Stats& s) {
  j[prefix + "rmse_" + unit] = s.rmse;
  j[prefix + "mean_" + unit] = s.mean;
  j[prefix + "median_" + unit] = s.median;
  j[prefix + "std_" + unit] = s.std;
  j[prefix + "min_" + unit] = s.min;
  j[prefix + "max_" + unit] = s.max;
}

}  // namespace

std::string format_table(const EvalResult& r) {
  std::ostringstream out;
  char buf[256];
  out << "ground truth   " << r.gt_name << " (" << r.gt_poses << " poses)\n";
  out << "estimate       " << r.est_name << " (" << r.est_poses << " poses)\n";
  out << "pairing        " << association_text(r) << ", " << r.association.est.size() << " pairs\n";
  out << "alignment      " << alignment_text(r) << '\n';
  std::snprintf(buf, sizeof buf, "length         %.3f m (ground truth path over the pairs)\n", r.length_m);
  out << buf;
  if (r.distance) {
    std::snprintf(buf, sizeof buf, "distance       %.3f m estimate, %.3f m ground truth (%+.3f %%; %zu steps of %g m)\n",
                  r.distance->estimate_m, r.distance->ground_truth_m, r.distance->error_pct, r.distance->steps,
                  r.distance->step_m);
    out << buf;
  }
  out << "duration       " << (r.duration_s ? opt(r.duration_s, 3) + " s" : std::string("n/a (no timestamps)"))
      << "\n\n";

  std::snprintf(buf, sizeof buf, "%-18s %11s %11s %11s %11s %11s %11s\n", "", "rmse", "mean", "median", "std", "min",
                "max");
  out << buf;
  stats_row(out, "ATE trans [m]", r.ate.translation, 4);
  stats_row(out, "ATE rot [deg]", r.ate.rotation, 4);
  if (r.ate_split) {
    stats_row(out, "ATE along [m]", r.ate_split->along, 4);
    stats_row(out, "ATE across [m]", r.ate_split->across, 4);
    stats_row(out, "ATE up [m]", r.ate_split->vertical, 4);
  }
  if (r.rpe) {
    stats_row(out, "RPE trans [m]", r.rpe->translation, 4);
    stats_row(out, "RPE rot [deg]", r.rpe->rotation, 4);
    std::snprintf(buf, sizeof buf, "  (RPE over %zu consecutive pairs %g %s apart)\n", r.rpe->pairs, r.rpe->options.delta,
                  to_string(r.rpe->options.unit));
    out << buf;
  } else {
    out << "RPE                n/a\n";
  }

  const KittiResult& k = r.kitti;
  std::snprintf(buf, sizeof buf, "\nKITTI odometry metric (devkit; first frame every %zu frames, %zu segments)\n",
                k.options.step, k.segments.size());
  out << buf;
  std::snprintf(buf, sizeof buf, "%-12s %9s %12s %16s\n", "length [m]", "segments", "trans [%]", "rot [deg/100m]");
  out << buf;
  for (const auto& l : k.per_length) {
    std::snprintf(buf, sizeof buf, "%-12.0f %9zu %12s %16s\n", l.length_m, l.segments,
                  opt(l.translational_pct, 4).c_str(), opt(l.rotational_deg_per_100m, 4).c_str());
    out << buf;
  }
  std::snprintf(buf, sizeof buf, "%-12s %9zu %12s %16s\n", "all", k.segments.size(),
                opt(k.translational_pct, 4).c_str(), opt(k.rotational_deg_per_100m, 4).c_str());
  out << buf;

  if (r.ate_split) {
    const Eigen::Vector3d& u = r.ate_split->up;
    std::snprintf(buf, sizeof buf,
                  "\nATE along / across / up: signed, in the ground truth's direction of travel (across: "
                  "+ to its left), up = (%g, %g, %g)\n",
                  u.x(), u.y(), u.z());
    out << buf;
  }

  if (!r.notes.empty()) {
    out << '\n';
    for (const auto& n : r.notes) out << "note: " << n << '\n';
  }
  return out.str();
}

Json to_json(const EvalResult& r) {
  using json = Json;
  json j;
  j["gt"] = {{"file", r.gt_name}, {"poses", r.gt_poses}};
  j["est"] = {{"file", r.est_name}, {"poses", r.est_poses}};
  j["poses_associated"] = r.association.est.size();
  json assoc = {
      {"method", !r.association.by_time ? "index" : (r.association.interpolated ? "interpolated" : "nearest")}};
  if (r.association.by_time) {
    if (r.association.interpolated) {
      assoc["max_gap_s"] = r.association_options.max_gap;
    } else {
      assoc["max_dt_s"] = r.association_options.max_dt;
    }
    assoc["est_time_offset_s"] = r.association_options.est_time_offset;
  }
  j["association"] = assoc;
  j["length_m"] = r.length_m;
  if (r.distance) {
    j["distance"] = {{"step_m", r.distance->step_m},
                     {"steps", r.distance->steps},
                     {"ground_truth_m", r.distance->ground_truth_m},
                     {"estimate_m", r.distance->estimate_m},
                     {"error_pct", r.distance->error_pct}};
  } else {
    j["distance"] = nullptr;
  }
  j["duration_s"] = opt_json(r.duration_s);

  const Similarity& T = r.alignment.transform;
  json R = json::array();
  for (int i = 0; i < 3; ++i) R.push_back({T.R(i, 0), T.R(i, 1), T.R(i, 2)});
  j["alignment"] = {{"mode", to_string(r.alignment.options.mode)},
                    {"first_n", r.alignment.options.first_n},
                    {"pairs_used", r.alignment.pairs_used},
                    {"scale", T.scale},
                    {"rotation", R},
                    {"translation", {T.t.x(), T.t.y(), T.t.z()}},
                    {"degenerate", T.degenerate}};

  json ate;
  put_stats(ate, "", "m", r.ate.translation);
  put_stats(ate, "rot_", "deg", r.ate.rotation);
  ate["count"] = r.ate.translation.count;
  j["ate"] = ate;
  if (r.ate_split) {
    json split;
    split["up"] = {r.ate_split->up.x(), r.ate_split->up.y(), r.ate_split->up.z()};
    put_stats(split, "along_", "m", r.ate_split->along);
    put_stats(split, "across_", "m", r.ate_split->across);
    put_stats(split, "up_", "m", r.ate_split->vertical);
    j["ate_split"] = split;
  } else {
    j["ate_split"] = nullptr;
  }

  if (r.rpe) {
    json rpe;
    rpe["delta"] = r.rpe->options.delta;
    rpe["delta_unit"] = to_string(r.rpe->options.unit);
    rpe["pairs"] = r.rpe->pairs;
    put_stats(rpe, "trans_", "m", r.rpe->translation);
    put_stats(rpe, "rot_", "deg", r.rpe->rotation);
    j["rpe"] = rpe;
  } else {
    j["rpe"] = nullptr;
  }

  const KittiResult& k = r.kitti;
  json per_length = json::array();
  for (const auto& l : k.per_length) {
    per_length.push_back({{"length_m", l.length_m},
                          {"segments", l.segments},
                          {"translational_pct", opt_json(l.translational_pct)},
                          {"rotational_deg_per_100m", opt_json(l.rotational_deg_per_100m)}});
  }
  j["kitti"] = {{"translational_pct", opt_json(k.translational_pct)},
                {"rotational_deg_per_100m", opt_json(k.rotational_deg_per_100m)},
                {"segments", k.segments.size()},
                {"step_frames", k.options.step},
                {"per_length", per_length}};
  j["notes"] = r.notes;
  return j;
}

}  // namespace liod::eval
