// Keyframe files and the keyframe store's spill directory. The graph's snapshot and journal are
// graph_journal.cpp (format, load) and state_writer.cpp (writing).
#include "liod/backend/map_store.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <system_error>

#include "state_io.hpp"

namespace liod {
namespace fs = std::filesystem;
using state_io::keyframe_path;

namespace {
constexpr char kKeyframeMagic[8] = {'L', 'I', 'O', 'D', 'K', 'F', 'R', '1'};
constexpr std::uint32_t kKeyframeVersion = 1;
}  // namespace

void write_file_atomically(const fs::path& path, std::string_view bytes) { state_io::write_file(path, bytes, true); }

void write_keyframe_file(const fs::path& directory, const BackendKeyframe& k, bool durable) {
  state_io::Encoder w;
  w.raw(kKeyframeMagic, 8);
  w.put(kKeyframeVersion);
  w.put(std::uint32_t{0});
  w.put(k.id);
  w.put(k.time);
  w.pose(k.odometry_pose);
  w.points(k.planes);
  w.points(k.edges);
  w.points(k.similarity);
  state_io::write_file(keyframe_path(directory, k.id), w.finish_file(), durable);
}

BackendKeyframe read_keyframe_file(const fs::path& directory, std::uint64_t id) {
  const fs::path path = keyframe_path(directory, id);
  if (!fs::exists(path)) throw StateError(path.string() + ": missing");
  const std::string bytes = state_io::read_all(path);
  state_io::Decoder k(bytes, path);
  k.check_file(kKeyframeMagic, kKeyframeVersion);
  BackendKeyframe kf;
  kf.id = k.get<std::uint64_t>();
  if (kf.id != id) k.fail("holds keyframe " + std::to_string(kf.id) + ", expected " + std::to_string(id));
  kf.time = k.get<double>();
  kf.odometry_pose = k.pose();
  kf.planes = k.points();
  kf.edges = k.points();
  kf.similarity = k.points();
  k.done();
  return kf;
}

KeyframeDirectory::KeyframeDirectory(fs::path directory, Kind kind) : directory_(std::move(directory)), kind_(kind) {
  std::error_code ec;
  fs::create_directories(directory_ / "keyframes", ec);
  if (ec) throw StateError(directory_.string() + ": cannot create the keyframe directory (" + ec.message() + ")");
}

KeyframeDirectory::~KeyframeDirectory() {
  if (kind_ != Kind::kScratch) return;
  std::error_code ec;  // best effort: a scratch directory left behind is only wasted space
  fs::remove_all(directory_, ec);
}

void KeyframeDirectory::write(const BackendKeyframe& keyframe) {
  // No fsync here: scratch files only have to survive until this process reads them back, and in
  // the state directory the StateWriter's one sync per keyframe makes the file durable before any
  // graph record names it.
  write_keyframe_file(directory_, keyframe, false);
}

BackendKeyframe KeyframeDirectory::read(std::uint64_t id) const { return read_keyframe_file(directory_, id); }

std::vector<std::uint32_t> read_map_runs(const fs::path& directory) {
  const fs::path path = directory / "map_runs";
  std::error_code ec;
  if (!fs::exists(path, ec)) return {0};
  std::istringstream in(state_io::read_all(path));
  std::vector<std::uint32_t> runs;
  std::uint64_t run = 0;
  while (in >> run) {
    if (run > std::numeric_limits<std::uint32_t>::max()) throw StateError(path.string() + ": run " + std::to_string(run) + " out of range");
    runs.push_back(static_cast<std::uint32_t>(run));
  }
  if (!in.eof()) throw StateError(path.string() + ": not a list of run numbers");
  return runs;
}

void write_map_runs(const fs::path& directory, const std::vector<std::uint32_t>& runs) {
  std::string text;
  for (const auto r : runs) text += std::to_string(r) + "\n";
  write_file_atomically(directory / "map_runs", text);
}

SavedMap saved_map(const PersistedGraph& graph, const std::vector<std::uint32_t>& map_runs) {
  SavedMap map;
  for (const auto& node : graph.nodes) {
    if (std::find(map_runs.begin(), map_runs.end(), node.run) == map_runs.end()) continue;
    map.ids.push_back(node.id);
    map.poses.push_back(node.pose);
  }
  return map;
}

}  // namespace liod
