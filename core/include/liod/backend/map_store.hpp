#pragma once
// Persistence of the backend (the one unit of liod_backend that touches files): keyframes, the
// pose graph and the global map in a state directory, written so that a crash or power loss at
// any point leaves the last complete state loadable:
//  - every file is written to `<name>.tmp`, fsync'ed, renamed over `<name>` and the directory
//    fsync'ed (rename is atomic on POSIX file systems: readers see the old or the new file);
//  - keyframe files (`keyframes/<id>.kf`, immutable) are written before `graph.bin`, which lists
//    them: graph.bin is the commit point, and it only ever names complete keyframe files;
//  - every file ends with a 64-bit FNV-1a checksum of its contents, so a torn or corrupted file
//    is detected and named in the error instead of being half-read.
// Layout: graph.bin, keyframes/*.kf, map.pcd (binary PCD, x y z float, as PCL reads it).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/pose_graph.hpp"

namespace liod {

/// A state directory that cannot be read: the message names the file and what is wrong.
class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes `bytes` to `path` atomically (temp file, fsync, rename, fsync of the directory).
/// Throws StateError.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// Writes points as a binary PCD (FIELDS x y z, float) atomically.
void write_map_pcd(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points);

/// Writes `keyframes/<id>.kf` under `directory` (the format load_state reads); `durable`: fsync
/// the file and the directory (a state directory), else only write-then-rename (scratch).
void write_keyframe_file(const std::filesystem::path& directory, const BackendKeyframe& keyframe, bool durable);
/// Reads and validates `keyframes/<id>.kf`. Throws StateError naming the file.
BackendKeyframe read_keyframe_file(const std::filesystem::path& directory, std::uint64_t id);

/// The keyframe store's spill in a directory: `keyframes/<id>.kf` files. In the state directory
/// (backend.persist) they are the persisted keyframes that graph.bin lists (durable writes); as
/// scratch (persistence off) the directory is created on construction and removed on
/// destruction.
class KeyframeDirectory final : public KeyframeSpill {
 public:
  enum class Kind { kState, kScratch };
  /// Creates the directory (and keyframes/); throws StateError when it cannot.
  KeyframeDirectory(std::filesystem::path directory, Kind kind);
  ~KeyframeDirectory() override;
  KeyframeDirectory(const KeyframeDirectory&) = delete;
  KeyframeDirectory& operator=(const KeyframeDirectory&) = delete;
  void write(const BackendKeyframe& keyframe) override;
  BackendKeyframe read(std::uint64_t id) const override;
  const std::filesystem::path& directory() const { return directory_; }

 private:
  std::filesystem::path directory_;
  Kind kind_;
};

struct PersistedState {
  std::vector<BackendKeyframe> keyframes;      // in node order
  std::vector<Eigen::Isometry3d> poses;        // optimised T_world_body per node
  std::vector<PoseGraphFactor> factors;
};

/// Incremental writer: each save() writes the keyframes not written before, then graph.bin.
class StateWriter {
 public:
  /// Creates the directory (and keyframes/) if needed and removes temp files a crash left.
  explicit StateWriter(std::filesystem::path directory);
  void save(const std::vector<BackendKeyframe>& keyframes, const PoseGraph& graph);
  /// Writes graph.bin only, naming keyframes `ids` whose files are already in the directory (a
  /// KeyframeDirectory on it wrote them as they arrived).
  void save_graph(const std::vector<std::uint64_t>& ids, const PoseGraph& graph);
  const std::filesystem::path& directory() const { return directory_; }

 private:
  std::filesystem::path directory_;
  std::size_t keyframes_written_ = 0;
};

/// Loads and validates a state directory (graph.bin and every keyframe it lists). Throws
/// StateError naming the file when one is missing, truncated, corrupt or inconsistent.
PersistedState load_state(const std::filesystem::path& directory);

}  // namespace liod
