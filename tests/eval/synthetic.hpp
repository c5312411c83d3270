#pragma once
// Small trajectories built by hand for the evaluator's tests.

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "liod/eval/trajectory.hpp"
#include "scratch_dir.hpp"

namespace liod::eval::test {

inline Eigen::Isometry3d pose(double x, double y, double z, double yaw = 0.0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(x, y, z);
  return p;
}

/// n poses 1 m apart along x.
inline Poses line(std::size_t n) {
  Poses p;
  for (std::size_t i = 0; i < n; ++i) p.push_back(pose(static_cast<double>(i), 0, 0));
  return p;
}

/// Stamps t0, t0 + dt, ...
inline Trajectory stamped(const Poses& poses, double t0, double dt, const std::string& name = "traj") {
  Trajectory t;
  t.name = name;
  t.poses = poses;
  for (std::size_t i = 0; i < poses.size(); ++i) t.stamps.push_back(t0 + dt * static_cast<double>(i));
  return t;
}

/// A 3-D curve with turns, climbs and a varying heading, so no alignment is degenerate.
inline Poses wiggly(std::size_t n, double step = 1.0) {
  Poses out;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = step * static_cast<double>(i);
    Eigen::Isometry3d p = pose(30.0 * std::sin(s / 40.0), s * 0.5, 2.0 * std::sin(s / 15.0), 0.0);
    p.linear() = (Eigen::AngleAxisd(s / 50.0, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.1 * std::sin(s / 7.0), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    out.push_back(p);
  }
  return out;
}

/// Writes text to a fresh file in the test program's scratch directory and returns its path.
inline std::string write_temp(const std::string& name, const std::string& text) {
  const std::filesystem::path path = ::liod::test::program_scratch_dir() / name;
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace liod::eval::test
