#pragma once
// Edge and planar feature selection by LOAM curvature with the seed paper's distance-adaptive
// neighbourhood: c = ||sum_{j in S} (X_i - X_j)|| / (|S| * ||X_i||), |S| = 10 / 8 / 6 / 4 for
// ranges <= 10 / <= 20 / <= 30 / > 30 m (the seed paper, "Distance-adaptive curvature").

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "liod/post_model.hpp"
#include "liod/types.hpp"

namespace liod {

enum class CurvatureNeighbourhood { kDistanceAdaptive, kFixed };

/// An axis-aligned box in the vehicle (body) frame; sensor points are mapped into it first.
struct CropBox {
  Eigen::Isometry3f sensor_to_body = Eigen::Isometry3f::Identity();
  Eigen::Vector3f min = Eigen::Vector3f::Zero();
  Eigen::Vector3f max = Eigen::Vector3f::Zero();
  bool contains(const Eigen::Vector3f& sensor_point) const {
    const Eigen::Vector3f p = sensor_to_body * sensor_point;
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  /// No point farther than this from the sensor lies in the box (its farthest corner, with a
  /// margin over float rounding): most returns skip the transform of contains() on their range.
  float reach() const {
    float farthest = 0.0F;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3f c((corner & 1) ? max.x() : min.x(), (corner & 2) ? max.y() : min.y(),
                              (corner & 4) ? max.z() : min.z());
      farthest = std::max(farthest, (c - sensor_to_body.translation()).norm());
    }
    return farthest * 1.001F + 1e-3F;
  }
};

struct FeatureParams {
  CurvatureNeighbourhood neighbourhood = CurvatureNeighbourhood::kDistanceAdaptive;
  double min_range_m = 2.0;
  double max_range_m = 120.0;
  double occlusion_jump_m = 0.5;  // at 10 m; scaled with range
  double edge_curvature = 0.1;
  double plane_curvature = 0.05;
  int sectors_per_ring = 8;
  int max_edges_per_sector = 6;
  /// An edge point that ends a surface seen at grazing incidence (the ring's range jumps beyond
  /// it) is moved on by this share of its step from the surface's previous return; 0: never. The
  /// surface ends somewhere between that return and the next, at a phase uniform over the step:
  /// half a step on average (surface_end_shift).
  double surface_end_extrapolation = 0.5;
  /// An edge that ends a ring's run of returns standing out before both neighbours, at most this
  /// wide (a post, a pole), is moved to post_depth_m before the run's axis (narrow_run_axis) along
  /// the horizontal ray, where the post model (map_correspondence.hpp) expects its surface; 0: never.
  double post_max_width_m = 0.0;
  double post_depth_m = kPostAxisDepthM;
  /// An edge where the ring runs off a surface across its top or bottom border (a guard rail's
  /// lower edge, a barrier's top) is dropped when the next ring up or down carries the surface on
  /// beyond it: within this of the horizontal line through the ring's last returns on it. Where a
  /// ring crosses a nearly horizontal border moves along the border with the sensor's pitch (the
  /// vehicle squats when it accelerates), so such an edge is no place along the road; 0: keep.
  double crossing_edge_tolerance_m = 0.0;
  std::optional<CropBox> self_crop;  // the vehicle's own body
};

/// |S| for a point at this range (both sides together).
int curvature_neighbourhood_size(double range_m, CurvatureNeighbourhood mode);

struct ScanFeatures {
  std::vector<std::uint32_t> edges;   // indices into Scan::points
  std::vector<std::uint32_t> planes;
  std::vector<float> plane_curvatures;  // each plane candidate's curvature, in the order of planes
  /// Per edge, in the order of edges (LiDAR frame): where its surface is expected to end, from the
  /// point; zero unless the edge ends a surface seen at grazing incidence (surface_end_shift).
  std::vector<Eigen::Vector3f> edge_shifts;
};

/// The last return on a surface before the ring's range jumps beyond it lies short of the
/// surface's end by up to one step between returns, at an unknown phase: on average half a step.
/// Face-on that step is a few centimetres, about the range noise; along a wall seen at grazing
/// incidence it is range x azimuth step / sin(grazing angle), 0.2-0.4 m for a tunnel's portal seen
/// from 15-25 m inside, and matched to the map's corner (seen face-on on the approach) every such
/// point pulled the scan towards the portal. Returns extrapolation x (end - previous) when the
/// step is over kMinGrazingStepRatio (5) x what the same turn of the ray makes face-on and over
/// kMinExtrapolatedStepM, else zero. end: the edge point; previous: the ring's return before it on
/// the same surface.
Eigen::Vector3f surface_end_shift(const Eigen::Vector3f& end, const Eigen::Vector3f& previous, double extrapolation);

/// The axis of a narrow object from one ring's returns on it, first..last (LiDAR frame, the sensor
/// at the origin, z up): for a centrally symmetric section (round, or square at any angle) the
/// extremes across the ray are symmetric about the axis, and the nearest point along the ray lies
/// as far before it as the extremes lie beside it (both are the section's support, in
/// perpendicular directions, equal for circles and squares). So the axis is midway across and half
/// the width behind the nearest return; the width is widened by one return's share, as the
/// extreme returns fall within the silhouette by half a step each on average. An edge point on
/// the post itself lies 0-11 cm before a 16 cm post's axis depending on the view and on which end
/// of the run it is; taken for a constant depth, that error repeats post after post.
/// Returns the axis at the returns' mean height; nothing for fewer than two returns, or for
/// returns deeper along the ray than wide (a grazing face's sliver, not a compact section).
std::optional<Eigen::Vector3f> narrow_run_axis(const float* x, const float* y, const float* z, int first, int last);

/// Reuses its buffers from scan to scan, so steady-state extraction does not allocate.
class FeatureExtractor {
 public:
  explicit FeatureExtractor(const FeatureParams& params)
      : params_(params), self_crop_reach_(params.self_crop ? params.self_crop->reach() : 0.0F) {}
  void extract(const Scan& scan, ScanFeatures& out);

 private:
  /// The widest curvature neighbourhood's half (10 returns: the nearest range band).
  static constexpr int kMaxHalf = 5;
  // One ring, in steps: its returns gathered, the gaps in its firing marked, occluded and
  // grazing returns excluded, the curvatures computed, then each sector's features picked.
  void process_ring(const Scan& scan, std::size_t ring_id, ScanFeatures& out);
  void mark_time_gaps(int n);
  /// Whether a missing return lies between ring positions a and b.
  bool across_gap(int a, int b) const;
  void exclude_occluded_and_parallel(int n);
  void ring_curvatures_by_range(int n);
  void pick_sector(const Scan& scan, std::size_t ring_id, int begin, int end, ScanFeatures& out);
  /// The shift of the edge at ring position k towards the end of its surface (surface_end_shift),
  /// or zero when it ends none.
  Eigen::Vector3f surface_end_step(int k, int n) const;
  /// The shift of the edge at k onto its narrow run's axis, post_depth_m before it, if k ends a
  /// run standing out before both of its neighbours (a post, a pole).
  std::optional<Eigen::Vector3f> post_run_shift(int k, int n) const;
  /// Whether the edge at k is where the ring runs off a surface across a horizontal border.
  bool crosses_border(const Scan& scan, std::size_t ring_id, int k, int n) const;
  /// Whether ring ring_id + step (step = -1, +1) carries the surface of the horizontal line
  /// through `end` and `inner` (the ring's last return on it, fired at end_time, and one before)
  /// on beyond `end`: two to four firings later (side +1) or earlier (side -1).
  bool surface_continues(const Scan& scan, std::size_t ring_id, int step, const Eigen::Vector2f& end,
                         const Eigen::Vector2f& inner, float end_time, int side) const;
  /// Copies the ring's coordinates, times and ranges into ring_*_ in ring order: the windows
  /// below then read consecutive floats instead of chasing indices into the scan.
  void gather_ring(const Scan& scan, const std::vector<std::uint32_t>& ring);

  FeatureParams params_;
  float self_crop_reach_;  // CropBox::reach of params_.self_crop
  std::vector<std::vector<std::uint32_t>> rings_;
  std::vector<float> range_;
  std::vector<float> ring_curvature_;
  std::vector<float> ring_x_, ring_y_, ring_z_, ring_time_, ring_range_;  // per ring position
  std::vector<int> gaps_before_;                                          // per ring position
  std::vector<std::uint8_t> excluded_;     // per ring position
  std::vector<std::uint8_t> range_jumps_;  // per ring position: an occlusion's jump to the next one
  /// A sector's feature candidates, sorted sharpest first; each carries its curvature so that the
  /// sort compares without looking it up.
  struct Candidate {
    float curvature;
    std::uint32_t position;  // in the ring
  };
  std::vector<Candidate> order_;
  /// Consecutive firings of one beam at 10 Hz (Helios: 1800 per turn).
  static constexpr float kFiringPeriodS = 55.56e-6F;
};

}  // namespace liod
