#pragma once
// Persistence of the backend (the units of liod_backend that touch files: map_store.cpp,
// graph_journal.cpp, state_writer.cpp): keyframes and the pose graph in a state directory,
// written so that a crash or power loss at any point leaves the last committed state loadable,
// and so that the bytes written per keyframe stay constant over a drive of any length.
// Layout (docs/backend.md, "Persistence"):
//  - `keyframes/<id>.kf`: one immutable file per keyframe (body-frame points), written once;
//    ids are unique across runs: each run continues after the largest id the directory holds;
//  - `graph.bin`: a snapshot of the graph (nodes with their run, optimised poses, factors by
//    keyframe id), FNV-1a checksum at the end, replaced only by temp file + rename;
//  - `journal.bin`: what happened since that snapshot, append-only, one CRC-32 per record (a
//    keyframe's node, an odometry or loop factor, an optimised-pose update); a torn last record
//    (a crash mid-append) is dropped on load, a corrupt one earlier is an error. When it outgrows
//    a multiple of the snapshot's size it is compacted: a new snapshot, then a fresh journal;
//  - `map_runs`: the runs whose poses are in the map's frame (the first, and those relocalised in
//    it), written only after their moved poses are durable in the journal.
// Ordering: every file the journal or the snapshot names is on disk before the record that
// names it (one sync per keyframe covers the keyframe file and the previous records), so a
// loaded state never names a missing keyframe file.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "liod/backend/keyframe_store.hpp"
#include "liod/backend/pose_graph.hpp"
#include "liod/backend/relocalization.hpp"

namespace liod {

/// A state directory that cannot be read: the message names the file and what is wrong.
class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes `bytes` to `path` atomically (temp file, fsync, rename, fsync of the directory).
/// Throws StateError.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// Writes `keyframes/<id>.kf` under `directory` (the format load_state reads), temp file and
/// rename; `durable`: also fsync the file and the directory (else a later sync covers it: the
/// StateWriter's in a state directory; none for scratch).
void write_keyframe_file(const std::filesystem::path& directory, const BackendKeyframe& keyframe, bool durable);
/// Reads and validates `keyframes/<id>.kf`. Throws StateError naming the file.
BackendKeyframe read_keyframe_file(const std::filesystem::path& directory, std::uint64_t id);

/// The keyframe store's spill in a directory: `keyframes/<id>.kf` files. In the state directory
/// (backend.persist) they are the persisted keyframes that the graph names (made durable by the
/// StateWriter's sync before any record names them); as scratch (persistence off) the directory
/// is created on construction and removed on destruction.
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

/// A graph node as persisted: the keyframe's id (its file's name), the run that made it (0 for
/// the first run into the directory, then 1, ...) and its optimised pose T_world_body. Each run's
/// poses are in that run's own world frame (its first keyframe's odometry frame).
struct GraphNode {
  std::uint64_t id = 0;
  std::uint32_t run = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

/// A relative-pose factor as persisted: between keyframe ids, not node indices, so that the
/// records of several runs combine.
struct GraphFactor {
  std::uint64_t from_id = 0;
  std::uint64_t to_id = 0;
  bool loop = false;
  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  Matrix6d information = Matrix6d::Identity();
};

/// The persisted graph of every run in a directory (snapshot + journal), without clouds.
struct PersistedGraph {
  std::vector<GraphNode> nodes;  // in the order added: the runs one after the other
  std::vector<GraphFactor> factors;
  std::unordered_map<std::uint64_t, std::size_t> node_index;  // keyframe id -> node
  std::uint64_t generation = 0;  // the snapshot's (0: none yet); the journal names the one it follows
  /// What the load recovered from (a torn last record dropped, a journal already folded into the
  /// snapshot ignored), one sentence each, for the log.
  std::vector<std::string> notes;
  bool journal_current = false;       // journal.bin exists and follows this snapshot
  std::uint64_t journal_valid_bytes = 0;  // where its intact records end (the writer appends there)

  std::uint32_t runs() const { return nodes.empty() ? 0 : nodes.back().run + 1; }
  /// Throws StateError (naming `where`) on a duplicate id or a factor naming an unknown node.
  void add_node(const GraphNode& node, const std::string& where);
  void add_factor(const GraphFactor& factor, const std::string& where);
  void update_pose(std::uint64_t id, const Eigen::Isometry3d& pose, const std::string& where);
};

/// Loads graph.bin and journal.bin (either may be missing: no snapshot yet, or no journal). Throws
/// StateError naming the file and the record when one is corrupt or inconsistent; a torn last
/// journal record is dropped and named in `notes`.
PersistedGraph load_graph(const std::filesystem::path& directory);

struct PersistedState {
  std::vector<BackendKeyframe> keyframes;  // in node order, every run
  std::vector<Eigen::Isometry3d> poses;    // optimised T_world_body per node (its run's world frame)
  std::vector<std::uint32_t> runs;         // the run of each node
  std::vector<PoseGraphFactor> factors;    // node indices into the above
  std::vector<std::string> notes;          // as PersistedGraph::notes
};

/// Loads and validates a state directory: the graph (load_graph) and every keyframe it names.
/// Throws StateError naming the file when one is missing, truncated, corrupt or inconsistent.
PersistedState load_state(const std::filesystem::path& directory);

/// The runs whose poses are in the map's frame (`map_runs`, one number per line): the run that
/// started the map and every run placed in it since; the others' poses are in their own frames.
/// A directory without the file holds one map, its first run's: {0}. Throws StateError.
std::vector<std::uint32_t> read_map_runs(const std::filesystem::path& directory);
/// Replaces `map_runs` atomically. Throws StateError.
void write_map_runs(const std::filesystem::path& directory, const std::vector<std::uint32_t>& runs);
/// The keyframes of `graph` in the map's frame, the map a new run relocalises in.
SavedMap saved_map(const PersistedGraph& graph, const std::vector<std::uint32_t>& map_runs);

struct StateWriterOptions {
  /// The journal is compacted into a new snapshot when it exceeds this multiple of the
  /// snapshot's size (and min_compact_bytes): each compaction writes the snapshot once per
  /// (ratio x snapshot) of journal, so the bytes per keyframe stay constant.
  double compact_ratio = 2.0;
  std::uint64_t min_compact_bytes = 1U << 20;
};

/// Counts of what the writer did, for tests and the log.
struct StateWriterStats {
  std::uint64_t syncs = 0;        // syncfs/fsync calls on the data path
  std::uint64_t compactions = 0;
  std::uint64_t journal_bytes = 0;  // journal.bin's current size
};

/// One run's writer into a state directory. Opening loads what earlier runs left (and clears the
/// temp files a crash left); this run's keyframe ids must start at first_keyframe_id(). Each
/// save appends the keyframes' nodes, new factors and changed optimised poses to the journal.
class StateWriter {
 public:
  /// Creates the directory (and keyframes/) if needed. Throws StateError when it cannot, or when
  /// the state there cannot be read (the caller decides; nothing is changed then).
  explicit StateWriter(std::filesystem::path directory, StateWriterOptions options = {});
  ~StateWriter();
  StateWriter(const StateWriter&) = delete;
  StateWriter& operator=(const StateWriter&) = delete;

  /// One past the largest keyframe id in the directory (graph or keyframe file): ids from here
  /// on are free.
  std::uint64_t first_keyframe_id() const { return first_id_; }
  /// This run's number (earlier runs are 0 .. run()-1).
  std::uint32_t run() const { return run_; }
  /// The state the directory held when opened (earlier runs), as loaded.
  const PersistedGraph& graph() const { return graph_; }

  /// Writes the keyframes not written before (no sync of their own), then save_graph.
  void save(const std::vector<BackendKeyframe>& keyframes, const PoseGraph& graph);
  /// Commits this run's graph: node k of `graph` is keyframe ids[k], whose file is already in the
  /// directory. One sync, which makes those files and the previous save durable; this save's
  /// records become durable with the next save or flush().
  void save_graph(const std::vector<std::uint64_t>& ids, const PoseGraph& graph);
  /// Makes everything saved durable now (end of a run).
  void flush();
  /// Compacts now, whatever the journal's size: a new snapshot of everything saved, then a fresh
  /// journal (saves compact by themselves when the journal outgrows StateWriterOptions).
  void compact();

  const std::filesystem::path& directory() const { return directory_; }
  const StateWriterStats& stats() const { return stats_; }

 private:
  std::string diff(const std::vector<std::uint64_t>& ids, const PoseGraph& graph);
  void sync();
  void open_journal();
  void start_fresh_journal();
  void append(const std::string& records);
  void start_compaction();
  void finish_compaction();

  std::filesystem::path directory_;
  StateWriterOptions options_;
  PersistedGraph graph_;      // every run's graph as persisted so far
  std::size_t run_begin_ = 0;  // graph_.nodes index of this run's first node
  std::size_t factors_saved_ = 0;  // of this run's PoseGraph
  std::uint64_t first_id_ = 0;
  std::uint32_t run_ = 0;
  std::size_t keyframes_written_ = 0;
  int journal_fd_ = -1;
  int directory_fd_ = -1;
  bool swap_pending_ = false;
  bool broken_ = false;       // a save failed part-way: no more saves this run  // a new snapshot is in place; journal.tmp replaces journal.bin next
  StateWriterStats stats_;
};

}  // namespace liod
