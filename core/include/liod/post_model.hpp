#pragma once
// The post model's one constant, shared by the feature extractor (which places a narrow run's edge
// on it) and the post correspondence (which takes the axis behind an edge).

namespace liod {

/// How far behind an edge point, along the horizontal ray that saw it, a post's axis lies: half
/// the depth of a typical roadside post (guard-rail C-posts, sign and lamp posts: 10-20 cm across).
/// The post model needs the axis, not the silhouette: the side a ring meets moves with the
/// viewpoint, the axis does not; a post a few centimetres thinner or thicker than this costs a
/// few centimetres of that motion, the same from every side.
constexpr double kPostAxisDepthM = 0.08;

}  // namespace liod
