#include "liod/daemon/map_export.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <ostream>
#include <stdexcept>

#include "liod/backend/map_store.hpp"
#include "liod/voxel_grid.hpp"

namespace liod {
namespace fs = std::filesystem;

namespace {

std::vector<Eigen::Vector3d> thinned(const std::vector<Eigen::Vector3d>& points, double voxel_m) {
  return voxel_m > 0.0 ? voxel_downsample(points, voxel_m) : points;
}

void fsync_path(const fs::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path.string() + ": cannot open for fsync (" + std::strerror(errno) + ")");
  const int rc = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  if (rc != 0) throw std::runtime_error(path.string() + ": fsync failed (" + std::strerror(error) + ")");
}

}  // namespace

void write_map_pcd(const fs::path& path, const std::vector<Eigen::Vector3d>& points) {
  std::string bytes = "# .PCD v0.7 - liod global map\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
                      std::to_string(points.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                      std::to_string(points.size()) + "\nDATA binary\n";
  bytes.reserve(bytes.size() + points.size() * 12);
  for (const auto& p : points) {
    for (int k = 0; k < 3; ++k) {
      const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(p[k]));
      for (int b = 0; b < 4; ++b) bytes.push_back(static_cast<char>((bits >> (8 * b)) & 0xFFU));
    }
  }
  // A reader (or a crash) never sees half a map: the temp file replaces the old map only once it
  // is on disk.
  const fs::path temp = path.string() + ".tmp";
  {
    std::ofstream f(temp, std::ios::binary | std::ios::trunc);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.flush();
    if (!f) throw std::runtime_error(temp.string() + ": cannot write the PCD");
  }
  fsync_path(temp, O_RDONLY);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    throw std::runtime_error(path.string() + ": rename from the temp file failed (" + std::strerror(errno) + ")");
  }
  fsync_path(path.has_parent_path() ? path.parent_path() : fs::path("."), O_RDONLY | O_DIRECTORY);
}

GlobalMap global_map_from_state(const fs::path& state_dir, double voxel_m) {
  // Thinning the running result whenever the buffer grows gives the map of one pass over all
  // points (voxel_downsample keeps the first point of each voxel) in the memory of the map.
  constexpr std::size_t kFlushPoints = 2'000'000;
  const PersistedGraph graph = load_graph(state_dir);
  GlobalMap map;
  map.runs = graph.runs();
  map.notes = graph.notes;
  std::size_t kept = 0;
  for (const GraphNode& node : graph.nodes) {
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
    return 0;
  } catch (const std::exception& e) {
    out << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace liod
