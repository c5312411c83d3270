#include "liod/daemon/backend_worker.hpp"

#include <spdlog/spdlog.h>

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "liod/backend/map_store.hpp"
#include "liod/daemon/map_export.hpp"

#include "liod/daemon/percentile.hpp"
#include "liod/angles.hpp"

namespace liod {

namespace {

// A process killed outright (SIGKILL, power loss) leaves its scratch directory behind; the next
// start removes those whose process is gone. A live process's, or one that cannot be told, stays.
void remove_orphaned_scratch(const std::filesystem::path& parent, std::string_view prefix) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || !it->is_directory(ec)) continue;
    int pid = 0;
    const char* digits = name.data() + prefix.size();
    const auto [rest, err] = std::from_chars(digits, name.data() + name.size(), pid);
    if (err != std::errc() || rest != name.data() + name.size() || pid <= 0 || pid == ::getpid()) continue;
    if (::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    const auto removed = fs::remove_all(it->path(), rm);
    if (rm) spdlog::warn("backend: could not remove {} left by process {}: {}", it->path().string(), pid, rm.message());
    else spdlog::info("backend: removed {} ({} files) left by process {}", it->path().string(), removed, pid);
  }
}

// The state directory's writer when persisting. A directory whose state cannot be read is left as
// it is (nothing of it is overwritten) and this run does not persist: the daemon still runs.
std::unique_ptr<StateWriter> open_state(const Config& config) {
  // Localising never writes: the saved map stays as the runs that made it left it.
  if (!config.backend.persist || config.backend.mode == BackendMode::kLocalize) return nullptr;
  try {
    auto writer = std::make_unique<StateWriter>(config.output.state_dir);
    for (const auto& note : writer->graph().notes) spdlog::warn("backend state: {}", note);
    spdlog::info("backend state in {}: {} keyframes from {} earlier run(s); this run is run {}, its keyframe ids start at {}",
                 config.output.state_dir, writer->graph().nodes.size(), writer->run(), writer->run(), writer->first_keyframe_id());
    return writer;
  } catch (const StateError& e) {
    spdlog::error("backend state not used, this run does not persist: {} (move the directory aside to start a new one)", e.what());
    return nullptr;
  }
}

// Where keyframe clouds beyond backend.memory_keyframes go. Persisting: the state directory's
// keyframe files, which the graph names anyway (each keyframe is written once). Otherwise a
// scratch directory under the state directory when it exists, else under the temp directory (a
// replay as an ordinary user usually cannot write /var/lib/liod), removed at exit; if neither can be created
// every cloud stays in memory (the backend works, only the memory bound is lost).
std::shared_ptr<KeyframeSpill> make_spill(const Config& config, bool persisting) {
  namespace fs = std::filesystem;
  if (persisting) {
    return std::make_shared<KeyframeDirectory>(config.output.state_dir, KeyframeDirectory::Kind::kState);
  }
  if (config.backend.memory_keyframes == 0) return nullptr;
  std::error_code ec;
  const std::pair<fs::path, std::string> places[] = {{fs::path(config.output.state_dir), "scratch-"},
                                                      {fs::temp_directory_path(ec), "liod-scratch-"}};
  for (const auto& [parent, prefix] : places) {
    // A replay must not create the daemon's state directory as a side effect.
    if (parent.empty() || !fs::is_directory(parent, ec)) continue;
    remove_orphaned_scratch(parent, prefix);
    const fs::path dir = parent / (prefix + std::to_string(::getpid()));
    try {
      auto spill = std::make_shared<KeyframeDirectory>(dir, KeyframeDirectory::Kind::kScratch);
      spdlog::info("backend: keyframe clouds beyond {} in memory go to {}", config.backend.memory_keyframes, dir.string());
      return spill;
    } catch (const StateError& e) {
      spdlog::debug("backend: no keyframe scratch directory here: {}", e.what());
    }
  }
  spdlog::warn("backend: no writable directory for keyframe clouds; all of them stay in memory");
  return nullptr;
}

// The saved map this run relocalises in: mapping, the state the writer loaded; localising, the
// state directory read as it is. None (a first run, or a directory that cannot be read) leaves a
// mapping run in its own frame, which then starts the map.
std::unique_ptr<Relocalizer> open_saved_map(const Config& config, const StateWriter* writer) {
  namespace fs = std::filesystem;
  const fs::path dir = config.output.state_dir;
  try {
    SavedMap map;
    if (writer) {
      map = saved_map(writer->graph(), read_map_runs(dir));
    } else if (config.backend.mode == BackendMode::kLocalize) {
      std::error_code ec;
      if (fs::is_directory(dir, ec)) map = saved_map(load_graph(dir), read_map_runs(dir));
      if (map.empty()) spdlog::error("backend: localise mode, but {} holds no map: poses stay flagged not_localized", dir.string());
    }
    if (map.empty()) return nullptr;
    spdlog::info("backend: relocalising in the saved map of {} keyframes in {}", map.ids.size(), dir.string());
    auto clouds = std::make_shared<KeyframeDirectory>(dir, KeyframeDirectory::Kind::kState);
    return std::make_unique<Relocalizer>(std::move(map), std::move(clouds), config);
  } catch (const StateError& e) {
    spdlog::error("backend: the saved map is not used: {}", e.what());
    return nullptr;
  }
}

}  // namespace

BackendWorker::BackendWorker(const Config& config, BackendWorkerOptions options)
    : config_(config),
      options_(std::move(options)),
      // The writer first: it clears the temp files a crash left in the state directory and
      // knows the first keyframe id that earlier runs left free.
      writer_(open_state(config)),
      backend_(config, make_spill(config, writer_ != nullptr), writer_ ? writer_->first_keyframe_id() : 0) {
  if (config.backend.persist || config.backend.mode == BackendMode::kLocalize) {
    backend_.use_saved_map(open_saved_map(config, writer_.get()));
  }
  correction_.localized = backend_.localized();
}

BackendWorker::~BackendWorker() = default;

bool BackendWorker::process(const Keyframe& keyframe) {
  const std::size_t checks_before = backend_.loop_checks().size();
  bool closed = false;
  if (options_.before_work) options_.before_work(keyframe);
  try {
    closed = backend_.add_keyframe(keyframe);
  } catch (const std::exception& e) {
    // A keyframe cloud that cannot be read back (its file removed or damaged) ends this loop
    // search; the graph already holds the keyframe and the next one searches again.
    spdlog::error("backend: keyframe {}: {}", keyframe.id, e.what());
  }
  const auto& checks = backend_.loop_checks();
  for (std::size_t i = checks_before; i < checks.size(); ++i) {
    const LoopCheck& c = checks[i];
    const auto& kf = backend_.keyframes();
    spdlog::debug("loop candidate {} -> {}: {} (similarity {:.2f} m = max({:.2f}, {:.2f}), rms {:.3f} m, inliers {:.2f}, dz {:.2f} m, tilt "
                  "{:.2f} deg, {:.0f} ms)",
                  kf.id(c.current), kf.id(c.candidate), to_string(c.outcome), c.similarity_m, c.similarity_forward_m,
                  c.similarity_backward_m, c.rms_m,
                  c.inlier_fraction, c.dz_m, c.tilt_deg, c.check_ms);
  }
  if (closed) {
    const LoopCheck& c = checks.back();
    const auto& kf = backend_.keyframes();
    spdlog::info("loop closed: keyframe {} -> {} ({:.1f} s earlier), correction now {:.2f} m, solve {:.1f} ms",
                 kf.id(c.current), kf.id(c.candidate), kf.time(c.current) - kf.time(c.candidate),
                 backend_.correction().translation().norm(), backend_.stats().solve_ms.back());
  }
  const bool newly_localized = backend_.localized() && !correction().localized;
  if (newly_localized) {
    const Eigen::Isometry3d t = backend_.correction();
    spdlog::info("relocalised in the saved map at keyframe {} ({} attempts, {} placements): map from odometry {:.2f} m, "
                 "yaw {:.1f} deg",
                 backend_.stats().localized_keyframe, backend_.stats().relocalization_attempts, backend_.stats().placements, t.translation().norm(),
                 std::atan2(t.linear()(1, 0), t.linear()(0, 0)) / kDegToRad);
  }
  if (backend_.correction_version() != published_version_) publish_correction();
  if (writer_) save_state();
  if (writer_ && backend_.localized() && !map_run_recorded_) record_map_run();
  return closed;
}

void BackendWorker::publish_correction() {
  published_version_ = backend_.correction_version();
  const Eigen::Isometry3d correction = backend_.correction();
  const bool localized = backend_.localized();
  std::lock_guard lock(correction_mutex_);
  correction_.map_from_odom = correction;
  correction_.localized = localized;
  ++correction_.sequence;
}

// Once this run is in the map's frame (it started the map, or was placed in it), its moved poses
// are made durable, then the run is listed in map_runs: a crash between the two leaves the run in
// its own frame, out of the map, never a run listed with poses in another frame.
void BackendWorker::record_map_run() {
  if (state_frozen_) return;
  try {
    writer_->flush();
    std::vector<std::uint32_t> runs = read_map_runs(writer_->directory());
    if (std::find(runs.begin(), runs.end(), writer_->run()) == runs.end()) runs.push_back(writer_->run());
    write_map_runs(writer_->directory(), runs);
    map_run_recorded_ = true;
  } catch (const StateError& e) {
    spdlog::warn("backend state no longer saved: {}", e.what());
    state_frozen_ = true;
  }
}

void BackendWorker::save_state() {
  // The graph may only name complete keyframe files: after a keyframe failed to reach the state
  // directory the last committed state stays.
  if (state_frozen_) return;
  const KeyframeStore& kf = backend_.keyframes();
  if (kf.spill_failures() > 0) {
    spdlog::warn("backend state no longer saved: a keyframe could not be written to {}", config_.output.state_dir);
    state_frozen_ = true;
    return;
  }
  try {
    writer_->save_graph(kf.ids(), backend_.graph());
  } catch (const StateError& e) {
    // The writer saves nothing more after a failure (its journal keeps the last commit).
    spdlog::warn("backend state no longer saved: {}", e.what());
    state_frozen_ = true;
  }
}

void BackendWorker::finish() {
  if (!writer_) return;
  save_state();
  try {
    if (!state_frozen_) writer_->flush();
    // This run's map only (the backend's keyframes); `liod map export` merges every run.
    write_map_pcd(writer_->directory() / "map.pcd", backend_.global_map(config_.backend.map_voxel_m));
  } catch (const std::exception& e) {
    spdlog::warn("backend state not saved: {}", e.what());
  }
}

MapCorrection BackendWorker::correction() const {
  std::lock_guard lock(correction_mutex_);
  return correction_;
}

std::string BackendWorker::summary() const {
  const auto& s = backend_.stats();
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  out << "backend: " << s.keyframes << " keyframes, " << s.loops_accepted << " loop closures, " << s.loops_rejected
      << " candidates rejected (";
  for (std::size_t i = 1; i < s.outcomes.size(); ++i) {
    if (i == static_cast<std::size_t>(LoopOutcome::kNoCandidate)) continue;
    out << (i > 2 ? ", " : "") << to_string(static_cast<LoopOutcome>(i)) << ' ' << s.outcomes[i];
  }
  out << ")\n";
  out << "backend: loop checks median " << percentile(s.check_ms, 0.5) << " ms, max " << percentile(s.check_ms, 1.0)
      << " ms; pose-graph solves " << s.solve_ms.size() << ", median " << percentile(s.solve_ms, 0.5) << " ms, max "
      << percentile(s.solve_ms, 1.0) << " ms\n";
  if (s.relocalization_attempts > 0 || !backend_.localized()) {
    out << "backend: " << (backend_.localized() ? "relocalised" : "not relocalised") << " in the saved map";
    if (backend_.localized()) out << " at keyframe " << s.localized_keyframe << ", t = " << std::setprecision(3) << s.localized_time;
    out << std::setprecision(1) << " (" << s.relocalization_attempts << " attempts, " << s.placements << " placements";
    if (config_.backend.mode == BackendMode::kLocalize) out << ", " << s.map_matches << " map matches";
    out << ")\n";
  }
  const KeyframeStore& kf = backend_.keyframes();
  out << "backend: keyframe clouds in memory " << kf.in_memory_count() << " of " << kf.size() << ", read back from disk "
      << kf.reads() << " times\n";
  return out.str();
}

}  // namespace liod
