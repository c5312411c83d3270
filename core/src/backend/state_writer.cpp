// StateWriter: one run's appends to a state directory's journal, and the compaction that keeps
// the bytes written per keyframe constant (map_store.hpp, docs/backend.md "Persistence").
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <system_error>

#include "journal_format.hpp"
#include "state_io.hpp"

namespace liod {
namespace fs = std::filesystem;

namespace {

// Temp files are what a crash mid-write leaves behind; the committed files never depend on them.
void remove_temp_files(const fs::path& directory) {
  std::error_code ec;
  for (const auto& dir : {directory, directory / "keyframes"}) {
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
    }
  }
}

// One past the largest id among the keyframe files, whether or not the graph names them (a run
// that died before its first commit leaves files no graph names; a new id must not reuse them).
std::uint64_t next_free_file_id(const fs::path& directory) {
  std::uint64_t next = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(directory / "keyframes", ec)) {
    if (entry.path().extension() != ".kf") continue;
    const std::string stem = entry.path().stem().string();
    std::uint64_t id = 0;
    const auto [end, err] = std::from_chars(stem.data(), stem.data() + stem.size(), id);
    if (err == std::errc() && end == stem.data() + stem.size()) next = std::max(next, id + 1);
  }
  return next;
}

}  // namespace

StateWriter::StateWriter(fs::path directory, StateWriterOptions options)
    : directory_(std::move(directory)), options_(options) {
  std::error_code ec;
  fs::create_directories(directory_ / "keyframes", ec);
  if (ec) throw StateError(directory_.string() + ": cannot create the state directory (" + ec.message() + ")");
  remove_temp_files(directory_);
  if (fs::exists(directory_ / "graph.bin") || fs::exists(directory_ / "journal.bin")) graph_ = load_graph(directory_);
  run_ = graph_.runs();
  run_begin_ = graph_.nodes.size();
  first_id_ = next_free_file_id(directory_);
  for (const auto& n : graph_.nodes) first_id_ = std::max(first_id_, n.id + 1);
  directory_fd_ = ::open(directory_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (directory_fd_ < 0) throw StateError(directory_.string() + ": cannot open (" + state_io::errno_text() + ")");
  open_journal();
}

StateWriter::~StateWriter() {
  try {
    if (!broken_) flush();
  } catch (const StateError&) {
    // The last save stays undurable; the state on disk is still the previous commit.
  }
  if (journal_fd_ >= 0) ::close(journal_fd_);
  if (directory_fd_ >= 0) ::close(directory_fd_);
}

void StateWriter::open_journal() {
  if (!graph_.journal_current) {
    start_fresh_journal();
    return;
  }
  const fs::path path = directory_ / "journal.bin";
  journal_fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (journal_fd_ < 0) throw StateError(path.string() + ": cannot open (" + state_io::errno_text() + ")");
  // A torn last record was dropped on load: the next record goes where it began.
  if (::ftruncate(journal_fd_, static_cast<off_t>(graph_.journal_valid_bytes)) != 0) {
    throw StateError(path.string() + ": cannot cut the torn record off (" + state_io::errno_text() + ")");
  }
  stats_.journal_bytes = graph_.journal_valid_bytes;
}

void StateWriter::start_fresh_journal() {
  // Once per run at most (a first run, or a journal a compaction left stale): durable at once.
  const fs::path path = directory_ / "journal.bin";
  write_file_atomically(path, journal::header(graph_.generation));
  journal_fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (journal_fd_ < 0) throw StateError(path.string() + ": cannot open (" + state_io::errno_text() + ")");
  stats_.journal_bytes = journal::kHeaderBytes;
}

void StateWriter::sync() {
  // syncfs, not fsync: one call makes the new keyframe files, their directory entries and the
  // journal's previous records durable together; per-file fsyncs would take three per keyframe.
  if (::syncfs(directory_fd_) != 0) throw StateError(directory_.string() + ": syncfs failed (" + state_io::errno_text() + ")");
  ++stats_.syncs;
}

void StateWriter::append(const std::string& records) {
  std::size_t done = 0;
  while (done < records.size()) {
    const ssize_t n = ::write(journal_fd_, records.data() + done, records.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw StateError((directory_ / "journal.bin").string() + ": append failed (" + state_io::errno_text() + ")");
    done += static_cast<std::size_t>(n);
  }
  stats_.journal_bytes += records.size();
}

void StateWriter::save(const std::vector<BackendKeyframe>& keyframes, const PoseGraph& graph) {
  for (; keyframes_written_ < keyframes.size(); ++keyframes_written_) {
    write_keyframe_file(directory_, keyframes[keyframes_written_], false);
  }
  std::vector<std::uint64_t> ids;
  ids.reserve(keyframes.size());
  for (const auto& k : keyframes) ids.push_back(k.id);
  save_graph(ids, graph);
}

std::string StateWriter::diff(const std::vector<std::uint64_t>& ids, const PoseGraph& graph) {
  const std::string where = (directory_ / "journal.bin").string();
  if (ids.size() != graph.size()) throw StateError(where + ": " + std::to_string(ids.size()) + " ids for " + std::to_string(graph.size()) + " nodes");
  const std::size_t saved = graph_.nodes.size() - run_begin_;
  if (graph.size() < saved || graph.factors().size() < factors_saved_) throw StateError(where + ": the graph lost nodes or factors");
  std::string records;
  // A solve moves the poses of its window: those, and only those, are written again.
  for (std::size_t i = 0; i < saved; ++i) {
    GraphNode& node = graph_.nodes[run_begin_ + i];
    if (node.pose.matrix() == graph.pose(i).matrix()) continue;
    node.pose = graph.pose(i);
    journal::append_pose_update(records, node.id, node.pose);
  }
  for (std::size_t i = saved; i < graph.size(); ++i) {
    if (ids[i] < first_id_) {
      throw StateError(where + ": keyframe id " + std::to_string(ids[i]) + " is below " + std::to_string(first_id_) +
                       ", the first id free in this directory");
    }
    const GraphNode node{ids[i], run_, graph.pose(i)};
    graph_.add_node(node, where);
    journal::append_node(records, node);
  }
  for (; factors_saved_ < graph.factors().size(); ++factors_saved_) {
    const PoseGraphFactor& f = graph.factors()[factors_saved_];
    const GraphFactor factor{ids[f.from], ids[f.to], f.loop, f.measured, f.information};
    graph_.add_factor(factor, where);
    journal::append_factor(records, factor);
  }
  return records;
}

void StateWriter::save_graph(const std::vector<std::uint64_t>& ids, const PoseGraph& graph) {
  if (broken_) throw StateError(directory_.string() + ": no longer saved after an earlier failure; the last commit stands");
  try {
    const std::string records = diff(ids, graph);
    const double limit = std::max(static_cast<double>(options_.min_compact_bytes),
                                  options_.compact_ratio * static_cast<double>(journal::snapshot_bytes(graph_.nodes.size(), graph_.factors.size())));
    if (!swap_pending_ && static_cast<double>(stats_.journal_bytes + records.size()) > limit) {
      start_compaction();  // this save's records are in the new snapshot
      return;
    }
    if (swap_pending_) {
      finish_compaction();
    } else {
      sync();
    }
    append(records);
  } catch (const StateError&) {
    // The in-memory graph may now be ahead of the journal: a later record could name a node the
    // journal lacks. Stop here; what is on disk is the last commit.
    broken_ = true;
    throw;
  }
}

void StateWriter::start_compaction() {
  // The new snapshot and the fresh journal are written as temp files and reach the disk with the
  // one sync of this keyframe; only then does graph.bin change. The old journal stays until the
  // next sync has made the new graph.bin durable (finish_compaction): a journal newer than its
  // snapshot must never be what a power loss leaves.
  const std::uint64_t generation = graph_.generation + 1;
  state_io::write_whole(directory_ / "graph.bin.tmp", journal::snapshot(graph_, generation), false);
  state_io::write_whole(directory_ / "journal.bin.tmp", journal::header(generation), false);
  sync();
  if (::rename((directory_ / "graph.bin.tmp").c_str(), (directory_ / "graph.bin").c_str()) != 0) {
    throw StateError((directory_ / "graph.bin").string() + ": rename failed (" + state_io::errno_text() + ")");
  }
  graph_.generation = generation;
  swap_pending_ = true;
  ++stats_.compactions;
}

void StateWriter::finish_compaction() {
  sync();
  const fs::path path = directory_ / "journal.bin";
  if (::rename((directory_ / "journal.bin.tmp").c_str(), path.c_str()) != 0) {
    throw StateError(path.string() + ": rename failed (" + state_io::errno_text() + ")");
  }
  ::close(journal_fd_);
  journal_fd_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (journal_fd_ < 0) throw StateError(path.string() + ": cannot open (" + state_io::errno_text() + ")");
  stats_.journal_bytes = journal::kHeaderBytes;
  swap_pending_ = false;
}

void StateWriter::compact() {
  if (broken_) throw StateError(directory_.string() + ": no longer saved after an earlier failure; the last commit stands");
  if (swap_pending_) finish_compaction();
  start_compaction();
  finish_compaction();
}

void StateWriter::flush() {
  if (broken_) return;
  if (swap_pending_) {
    finish_compaction();
    sync();  // the journal's rename
  } else {
    sync();
  }
}

}  // namespace liod
