#pragma once
// The global map from a state directory (`liod map export`, and the backend's map.pcd at the end
// of a run): every keyframe's points at its optimised pose, voxel-downsampled, as a binary PCD
// that PCL and CloudCompare open (test_pcd_compat reads it with PCL). The PCD is written here
// rather than by PCL: Debian's libpcl_io links VTK, OpenNI and OpenNI2, whose start-up code would
// run in the daemon (and trips ThreadSanitizer), for a header and one array of floats.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace liod {

struct MapExportOptions {
  std::string state_dir;  ///< a state directory (output.state_dir of a run with backend.persist)
  std::string out;        ///< the PCD to write
  double voxel_m = 0.3;   ///< downsampling of the merged map; 0 = every stored point
};

/// Writes `points` as a binary PCD (FIELDS x y z, float, little-endian as on x86-64 and ARM64),
/// atomically: a temp file, fsync'ed, renamed over `path`. Throws StateError naming the file.
void write_map_pcd(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points);

struct GlobalMap {
  std::vector<Eigen::Vector3d> points;
  std::size_t keyframes = 0;
  std::uint32_t runs = 0;
  std::size_t runs_left_out_keyframes = 0;  // keyframes of runs not in the map's frame
  std::vector<std::string> notes;  // what loading the graph recovered from (PersistedGraph::notes)
};

/// Every keyframe in `state_dir` of the runs in the map's frame (map_runs: the first and those
/// relocalised in it; planes and edges) at its optimised pose, merged and voxel-downsampled as it
/// goes (one keyframe file in memory at a time). Throws StateError when the directory cannot be read.
GlobalMap global_map_from_state(const std::filesystem::path& state_dir, double voxel_m);

/// `liod map export`: prints a summary line to `out`; returns 0, or 1 after printing the error.
int run_map_export(const MapExportOptions& options, std::ostream& out);

}  // namespace liod
