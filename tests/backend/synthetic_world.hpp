#pragma once
// Synthetic scenes for the backend tests: surfaces sampled as point clouds (no occlusion; every
// surface within range is "seen"), and keyframes built from them as the front end would.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/loop_closure.hpp"
#include "liod/lidar_inertial_odometry.hpp"
#include "liod/voxel_grid.hpp"

namespace liod::test {

struct Box {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
};

struct World {
  std::vector<Eigen::Vector3d> planes;  // surface samples
  std::vector<Eigen::Vector3d> edges;   // vertical box edges
};

inline void add_box(World& w, const Box& b, double step) {
  for (double z = b.min.z(); z <= b.max.z(); z += step) {
    for (double x = b.min.x(); x <= b.max.x(); x += step) {
      w.planes.emplace_back(x, b.min.y(), z);
      w.planes.emplace_back(x, b.max.y(), z);
    }
    for (double y = b.min.y(); y <= b.max.y(); y += step) {
      w.planes.emplace_back(b.min.x(), y, z);
      w.planes.emplace_back(b.max.x(), y, z);
    }
    for (double x : {b.min.x(), b.max.x()}) {
      for (double y : {b.min.y(), b.max.y()}) w.edges.emplace_back(x, y, z);
    }
  }
}

inline void add_ground(World& w, double x0, double x1, double y0, double y1, double z, double step) {
  for (double x = x0; x <= x1; x += step) {
    for (double y = y0; y <= y1; y += step) w.planes.emplace_back(x, y, z);
  }
}

/// Buildings of random width, depth, height and setback along a line y = side (facing the road).
inline void add_facade_row(World& w, double x0, double x1, double side, double direction, std::mt19937& rng, double step) {
  std::uniform_real_distribution<double> width(4.0, 12.0), gap(1.0, 4.0), setback(0.0, 2.5), height(4.0, 12.0);
  for (double x = x0; x < x1;) {
    const double wd = width(rng);
    const double near = side + direction * setback(rng);
    const double far = near + direction * 8.0;
    add_box(w, {Eigen::Vector3d(x, std::min(near, far), 0.0), Eigen::Vector3d(x + wd, std::max(near, far), height(rng))}, step);
    x += wd + gap(rng);
  }
}

/// A keyframe as the front end would produce it: points of `world` within `range` of the true
/// pose, expressed in the odometry frame through the odometry pose (the front end's estimate).
inline Keyframe make_keyframe(const World& world, const Eigen::Isometry3d& truth, const Eigen::Isometry3d& odometry,
                              std::uint64_t id, double time, double range = 35.0) {
  Keyframe k;
  k.id = id;
  k.state.time = time;
  k.state.rotation = odometry.linear();
  k.state.position = odometry.translation();
  const Eigen::Isometry3d body_from_world = truth.inverse();
  auto take = [&](const std::vector<Eigen::Vector3d>& in, std::vector<Eigen::Vector3d>& out) {
    for (const auto& p : in) {
      const Eigen::Vector3d b = body_from_world * p;
      if (b.norm() < range && b.norm() > 1.0) out.push_back(odometry * b);
    }
  };
  take(world.planes, k.planes_world);
  take(world.edges, k.edges_world);
  k.similarity_cloud_world = k.planes_world;
  k.similarity_cloud_world.insert(k.similarity_cloud_world.end(), k.edges_world.begin(), k.edges_world.end());
  k.similarity_cloud_world = voxel_downsample(k.similarity_cloud_world, 1.0);
  return k;
}

/// What Backend::add_keyframe stores of a keyframe: its points in its body frame, voxel-thinned.
inline BackendKeyframe to_backend(const Keyframe& k, double voxel) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = k.state.rotation;
  pose.translation() = k.state.position;
  const Eigen::Isometry3d inv = pose.inverse();
  auto body = [&](const std::vector<Eigen::Vector3d>& w, double v) {
    std::vector<Eigen::Vector3d> b;
    for (const auto& p : w) b.push_back(inv * p);
    if (v > 0) b = voxel_downsample(b, v);
    std::vector<Eigen::Vector3f> out;
    for (const auto& p : b) out.push_back(p.cast<float>());
    return out;
  };
  BackendKeyframe out;
  out.id = k.id;
  out.time = k.state.time;
  out.odometry_pose = pose;
  out.planes = body(k.planes_world, voxel);
  out.edges = body(k.edges_world, voxel);
  out.similarity = body(k.similarity_cloud_world, 0.0);
  return out;
}

inline Eigen::Isometry3d pose_xyz_yaw(double x, double y, double z, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

}  // namespace liod::test
