#pragma once
// A synthetic backend state for the persistence tests: keyframes in a row with small clouds,
// odometry factors between neighbours and now and then a loop factor, in a PoseGraph as the
// backend keeps it.
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "liod/backend/map_store.hpp"
#include "scratch_dir.hpp"

namespace liod::test {

struct StateFixture {
  std::uint64_t first_id = 0;  // the writer's first_keyframe_id()
  std::size_t points = 200;    // plane points per keyframe
  std::vector<BackendKeyframe> keyframes;
  PoseGraph graph;
};

/// Grows the fixture to `n` keyframes (ids first_id, first_id + 1, ...); every 7th factor is a loop.
inline void grow(StateFixture& f, std::size_t n) {
  for (std::size_t i = f.keyframes.size(); i < n; ++i) {
    BackendKeyframe k;
    k.id = f.first_id + i;
    k.time = 0.5 * static_cast<double>(i);
    k.odometry_pose.translation() = Eigen::Vector3d(static_cast<double>(i), 0.5, 0.0);
    for (std::size_t j = 0; j < f.points; ++j) k.planes.emplace_back(static_cast<float>(j), static_cast<float>(i), 1.0F);
    k.edges.emplace_back(1.0F, 2.0F, 3.0F);
    k.similarity.emplace_back(4.0F, 5.0F, 6.0F);
    f.keyframes.push_back(k);
    f.graph.add_node(k.odometry_pose);
    if (i > 0) {
      PoseGraphFactor factor;
      factor.from = i - 1;
      factor.to = i;
      factor.measured.translation() = Eigen::Vector3d(1, 0, 0);
      factor.information = relative_pose_information(0.05, 0.01);
      factor.loop = i % 7 == 0;
      f.graph.add_factor(factor);
    }
  }
}

/// What a solve does to the graph: moves the newest `window` poses.
inline void bend(StateFixture& f, std::size_t window, double dy) {
  const std::size_t n = f.graph.size();
  for (std::size_t i = n > window ? n - window : 0; i < n; ++i) {
    Eigen::Isometry3d p = f.graph.pose(i);
    p.translation().y() += dy;
    f.graph.set_pose(i, p);
  }
}

inline std::filesystem::path fresh_state_dir(const std::string& name) {
  const std::filesystem::path dir = program_scratch_dir() / name;
  std::filesystem::remove_all(dir);
  return dir;
}

inline std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace liod::test
