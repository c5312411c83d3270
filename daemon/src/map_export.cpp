#include <algorithm>
#include "liod/daemon/map_export.hpp"

#include <bit>
#include <cstdint>
#include <ostream>
#include <stdexcept>

#include "liod/backend/map_store.hpp"
#include "liod/drivers/byte_order.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace fs = std::filesystem;

namespace {

std::vector<Eigen::Vector3d> thinned(const std::vector<Eigen::Vector3d>& points, double voxel_m) {
  return voxel_m > 0.0 ? voxel_downsample(points, voxel_m) : points;
}

}  // namespace

void write_map_pcd(const fs::path& path, const std::vector<Eigen::Vector3d>& points) {
  std::string bytes = "# .PCD v0.7 - liod global map\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
                      std::to_string(points.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                      std::to_string(points.size()) + "\nDATA binary\n";
  const std::size_t header = bytes.size();
  bytes.resize(header + points.size() * 12);
  auto* out = reinterpret_cast<std::uint8_t*>(bytes.data() + header);
  for (const auto& p : points) {
    for (int k = 0; k < 3; ++k, out += 4) drivers::store_le32(out, std::bit_cast<std::uint32_t>(static_cast<float>(p[k])));
  }
  // A reader (or a crash) never sees half a map: the temp file replaces the old map only once it
  // is on disk.
  write_file_atomically(path, bytes);
}

GlobalMap global_map_from_state(const fs::path& state_dir, double voxel_m) {
  // Thinning the running result whenever the buffer grows gives the map of one pass over all
  // points (voxel_downsample keeps the first point of each voxel) in the memory of the map.
  constexpr std::size_t kFlushPoints = 2'000'000;
  const PersistedGraph graph = load_graph(state_dir);
  // Only the runs in the map's frame: a run never placed in it has poses in a frame of its own.
  const std::vector<std::uint32_t> map_runs = read_map_runs(state_dir);
  GlobalMap map;
  map.runs = graph.runs();
  map.notes = graph.notes;
  std::size_t kept = 0;
  for (const GraphNode& node : graph.nodes) {
    if (std::find(map_runs.begin(), map_runs.end(), node.run) == map_runs.end()) {
      ++map.runs_left_out_keyframes;
      continue;
    }
    const BackendKeyframe kf = read_keyframe_file(state_dir, node.id);
    for (const auto& p : kf.planes) map.points.push_back(node.pose * p.cast<double>());
    for (const auto& p : kf.edges) map.points.push_back(node.pose * p.cast<double>());
    ++map.keyframes;
    if (voxel_m > 0.0 && map.points.size() - kept > kFlushPoints) {
      map.points = thinned(map.points, voxel_m);
      kept = map.points.size();
    }
  }
  map.points = thinned(map.points, voxel_m);
  return map;
}

int run_map_export(const MapExportOptions& options, std::ostream& out) {
  try {
    const GlobalMap map = global_map_from_state(options.state_dir, options.voxel_m);
    for (const auto& note : map.notes) out << "note: " << note << '\n';
    write_map_pcd(options.out, map.points);
    out << "map: " << map.points.size() << " points from " << map.keyframes << " keyframes of " << map.runs << " run(s), voxel "
        << options.voxel_m << " m -> " << options.out << '\n';
    if (map.runs_left_out_keyframes > 0) {
      out << "map: " << map.runs_left_out_keyframes << " keyframes of runs never relocalised in the map left out (their frames are their own)\n";
    }
    return 0;
  } catch (const std::exception& e) {
    out << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace liod
