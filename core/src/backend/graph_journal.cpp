// The graph's snapshot (graph.bin) and journal (journal.bin): their encoding and their loading.
#include <algorithm>
#include <cstring>

#include "journal_format.hpp"
#include "state_io.hpp"

namespace liod {
namespace fs = std::filesystem;

namespace {

constexpr char kGraphMagic[8] = {'L', 'I', 'O', 'D', 'G', 'R', 'F', '1'};
constexpr char kJournalMagic[8] = {'L', 'I', 'O', 'D', 'J', 'R', 'N', '1'};
constexpr std::uint32_t kGraphVersion = 2;
constexpr std::uint32_t kJournalVersion = 1;
// A record's payload is at most a factor's: larger lengths are corruption, not data.
constexpr std::uint32_t kMaxPayload = 8 + 8 + state_io::kPoseBytes + 36 * sizeof(double);

void put_factor_payload(state_io::Encoder& w, const GraphFactor& f) {
  w.put(f.from_id);
  w.put(f.to_id);
  w.pose(f.measured);
  w.raw(f.information.data(), sizeof(double) * 36);
}

GraphFactor get_factor_payload(state_io::Decoder& r, bool loop) {
  GraphFactor f;
  f.from_id = r.get<std::uint64_t>();
  f.to_id = r.get<std::uint64_t>();
  f.loop = loop;
  f.measured = r.pose();
  for (int k = 0; k < 36; ++k) f.information.data()[k] = r.get<double>();
  if (!f.information.allFinite()) r.fail("a factor with a non-finite information matrix");
  return f;
}

void frame(std::string& out, journal::RecordType type, const std::string& payload) {
  state_io::Encoder w;
  w.put(static_cast<std::uint32_t>(payload.size()));
  w.put(static_cast<std::uint8_t>(type));
  w.raw(payload.data(), payload.size());
  w.put(state_io::crc32(w.bytes()));
  out += w.bytes();
}

std::string record_name(const fs::path& path, std::size_t index, std::size_t offset) {
  return path.filename().string() + " record " + std::to_string(index) + " at byte " + std::to_string(offset);
}

void apply_record(PersistedGraph& g, journal::RecordType type, std::string_view payload, const std::string& where) {
  state_io::Decoder r(payload, where);
  switch (type) {
    case journal::RecordType::kNode: {
      GraphNode n;
      n.id = r.get<std::uint64_t>();
      n.run = r.get<std::uint32_t>();
      n.pose = r.pose();
      r.done();
      g.add_node(n, where);
      return;
    }
    case journal::RecordType::kOdometryFactor:
    case journal::RecordType::kLoopFactor: {
      const GraphFactor f = get_factor_payload(r, type == journal::RecordType::kLoopFactor);
      r.done();
      g.add_factor(f, where);
      return;
    }
    case journal::RecordType::kPoseUpdate: {
      const auto id = r.get<std::uint64_t>();
      const Eigen::Isometry3d pose = r.pose();
      r.done();
      g.update_pose(id, pose, where);
      return;
    }
  }
  throw StateError(where + ": unknown record type " + std::to_string(static_cast<int>(type)));
}

bool all_zero(std::string_view bytes) {
  return std::all_of(bytes.begin(), bytes.end(), [](char c) { return c == 0; });
}

void load_snapshot(const fs::path& path, PersistedGraph& g) {
  const std::string bytes = state_io::read_all(path);
  state_io::Decoder r(bytes, path);
  r.check_file(kGraphMagic, kGraphVersion);
  g.generation = r.get<std::uint64_t>();
  const auto nodes = r.count();
  const std::string where = path.string();
  for (std::uint64_t i = 0; i < nodes; ++i) {
    GraphNode n;
    n.id = r.get<std::uint64_t>();
    n.run = r.get<std::uint32_t>();
    n.pose = r.pose();
    g.add_node(n, where);
  }
  const auto factors = r.count();
  for (std::uint64_t i = 0; i < factors; ++i) {
    const bool loop = r.get<std::uint8_t>() != 0;
    g.add_factor(get_factor_payload(r, loop), where);
  }
  r.done();
}

// The records after the header, applied in order. The end of the file may hold a torn record
// (the process or the machine died mid-append: the record runs past the end, fails its CRC as
// the very last one, or is followed by nothing but zeros, which is what a power loss leaves in a
// file extended but not yet written); it is dropped and named in `notes`. A record that fails its
// CRC with intact data after it is corruption, and an error.
void load_records(const fs::path& path, std::string_view bytes, PersistedGraph& g) {
  std::size_t offset = journal::kHeaderBytes;
  for (std::size_t index = 0; offset < bytes.size(); ++index) {
    const std::string where = record_name(path, index, offset);
    const std::string_view rest = bytes.substr(offset);
    std::uint32_t length = 0;
    if (rest.size() >= 4) std::memcpy(&length, rest.data(), 4);
    // A prefix of a record keeps its length field, so an implausible length is corruption.
    if (rest.size() >= 4 && length > kMaxPayload && !all_zero(rest)) {
      throw StateError(path.string() + ": " + where + ": implausible record length " + std::to_string(length) + ": the journal is corrupt");
    }
    const bool complete = rest.size() >= journal::kFramingBytes && length + journal::kFramingBytes <= rest.size();
    const std::size_t size = complete ? length + journal::kFramingBytes : rest.size();
    std::uint32_t stored = 0;
    if (complete) std::memcpy(&stored, rest.data() + size - 4, 4);
    if (!complete || stored != state_io::crc32(rest.substr(0, size - 4))) {
      if (size == rest.size() || all_zero(rest)) {
        g.notes.push_back(path.string() + ": " + where + ": torn (" + std::to_string(rest.size()) +
                          " bytes at the end, a crash while appending): dropped; the records before it are loaded");
        return;
      }
      throw StateError(path.string() + ": " + where + ": checksum mismatch: the journal is corrupt");
    }
    g.journal_valid_bytes = offset + size;
    apply_record(g, static_cast<journal::RecordType>(rest[4]), rest.substr(5, length), path.string() + ": " + where);
    offset += size;
  }
}

void load_journal(const fs::path& path, PersistedGraph& g) {
  const std::string bytes = state_io::read_all(path);
  if (bytes.size() < journal::kHeaderBytes) {
    // A fresh journal's header reaches the disk before the journal replaces the old one; a
    // shorter file is a header torn by a crash while the directory was being set up.
    g.notes.push_back(path.string() + ": torn header (" + std::to_string(bytes.size()) + " bytes): no records");
    return;
  }
  if (std::memcmp(bytes.data(), kJournalMagic, 8) != 0) throw StateError(path.string() + ": not a liod journal (bad magic)");
  std::uint32_t version = 0;
  std::uint64_t generation = 0;
  std::uint32_t stored = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&generation, bytes.data() + 16, 8);
  std::memcpy(&stored, bytes.data() + 24, 4);
  if (stored != state_io::crc32(std::string_view(bytes).substr(0, 24))) throw StateError(path.string() + ": header checksum mismatch");
  if (version != kJournalVersion) throw StateError(path.string() + ": unsupported version " + std::to_string(version));
  if (generation > g.generation) {
    throw StateError(path.string() + ": follows snapshot " + std::to_string(generation) + ", but graph.bin is snapshot " +
                     std::to_string(g.generation) + " (graph.bin is older than the journal)");
  }
  if (generation < g.generation) {
    // A compaction put the new snapshot in place and died before replacing the journal: every
    // record here is already in graph.bin.
    g.notes.push_back(path.string() + ": follows snapshot " + std::to_string(generation) + ", already folded into graph.bin (snapshot " +
                      std::to_string(g.generation) + "): ignored");
    return;
  }
  g.journal_current = true;
  g.journal_valid_bytes = journal::kHeaderBytes;
  load_records(path, bytes, g);
}

}  // namespace

void PersistedGraph::add_node(const GraphNode& node, const std::string& where) {
  if (!node_index.emplace(node.id, nodes.size()).second) {
    throw StateError(where + ": keyframe " + std::to_string(node.id) + " is in the graph twice");
  }
  if (!nodes.empty() && node.run < nodes.back().run) throw StateError(where + ": a node of run " + std::to_string(node.run) + " after a later run's");
  nodes.push_back(node);
}

void PersistedGraph::add_factor(const GraphFactor& factor, const std::string& where) {
  if (node_index.count(factor.from_id) == 0 || node_index.count(factor.to_id) == 0) {
    throw StateError(where + ": a factor names keyframe " + std::to_string(factor.from_id) + " or " + std::to_string(factor.to_id) +
                     ", which is not in the graph");
  }
  factors.push_back(factor);
}

void PersistedGraph::update_pose(std::uint64_t id, const Eigen::Isometry3d& pose, const std::string& where) {
  const auto it = node_index.find(id);
  if (it == node_index.end()) throw StateError(where + ": a pose update for keyframe " + std::to_string(id) + ", which is not in the graph");
  nodes[it->second].pose = pose;
}

namespace journal {

void append_node(std::string& out, const GraphNode& node) {
  state_io::Encoder w;
  w.put(node.id);
  w.put(node.run);
  w.pose(node.pose);
  frame(out, RecordType::kNode, w.bytes());
}

void append_factor(std::string& out, const GraphFactor& factor) {
  state_io::Encoder w;
  put_factor_payload(w, factor);
  frame(out, factor.loop ? RecordType::kLoopFactor : RecordType::kOdometryFactor, w.bytes());
}

void append_pose_update(std::string& out, std::uint64_t id, const Eigen::Isometry3d& pose) {
  state_io::Encoder w;
  w.put(id);
  w.pose(pose);
  frame(out, RecordType::kPoseUpdate, w.bytes());
}

std::string header(std::uint64_t generation) {
  state_io::Encoder w;
  w.raw(kJournalMagic, 8);
  w.put(kJournalVersion);
  w.put(std::uint32_t{0});
  w.put(generation);
  w.put(state_io::crc32(w.bytes()));
  return std::move(w.bytes());
}

std::string snapshot(const PersistedGraph& graph, std::uint64_t generation) {
  state_io::Encoder w;
  w.bytes().reserve(snapshot_bytes(graph.nodes.size(), graph.factors.size()));
  w.raw(kGraphMagic, 8);
  w.put(kGraphVersion);
  w.put(std::uint32_t{0});
  w.put(generation);
  w.put(static_cast<std::uint64_t>(graph.nodes.size()));
  for (const auto& n : graph.nodes) {
    w.put(n.id);
    w.put(n.run);
    w.pose(n.pose);
  }
  w.put(static_cast<std::uint64_t>(graph.factors.size()));
  for (const auto& f : graph.factors) {
    w.put(static_cast<std::uint8_t>(f.loop ? 1 : 0));
    put_factor_payload(w, f);
  }
  return w.finish_file();
}

std::uint64_t snapshot_bytes(std::size_t nodes, std::size_t factors) {
  return 8 + 4 + 4 + 8 + 8 + nodes * (8 + 4 + state_io::kPoseBytes) + 8 + factors * (1 + kMaxPayload) + 8;
}

}  // namespace journal

PersistedGraph load_graph(const fs::path& directory) {
  PersistedGraph g;
  const fs::path snapshot = directory / "graph.bin";
  const fs::path journal = directory / "journal.bin";
  const bool have_snapshot = fs::exists(snapshot);
  if (have_snapshot) load_snapshot(snapshot, g);
  if (fs::exists(journal)) {
    load_journal(journal, g);
  } else if (!have_snapshot) {
    throw StateError(snapshot.string() + ": missing, and no journal.bin (no state was saved here)");
  }
  return g;
}

PersistedState load_state(const fs::path& directory) {
  PersistedGraph g = load_graph(directory);
  PersistedState state;
  state.notes = std::move(g.notes);
  for (const auto& n : g.nodes) {
    const fs::path path = state_io::keyframe_path(directory, n.id);
    if (!fs::exists(path)) throw StateError(path.string() + ": missing, but named by the graph in " + directory.string());
    state.keyframes.push_back(read_keyframe_file(directory, n.id));
    state.poses.push_back(n.pose);
    state.runs.push_back(n.run);
  }
  for (const auto& f : g.factors) {
    PoseGraphFactor p;
    p.from = g.node_index.at(f.from_id);
    p.to = g.node_index.at(f.to_id);
    p.loop = f.loop;
    p.measured = f.measured;
    p.information = f.information;
    state.factors.push_back(p);
  }
  return state;
}

}  // namespace liod
