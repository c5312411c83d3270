#pragma once
// The backend thread's work (issue 5): the pure liod::Backend plus what a live daemon needs
// around it — the directory where keyframe clouds beyond backend.memory_keyframes live,
// persistence of keyframes/graph/map into output.state_dir (if backend.persist),
// a log line per loop, and the latest correction T_world_odom published for other threads.
// The Pipeline's backend thread calls process() for each keyframe and finish() at the end; the
// odometry never waits for it (the keyframe ring is lossy live), and no lock is held across an
// optimisation: the correction is copied under a mutex only after a solve finished.

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "liod/backend/backend.hpp"
#include "liod/config.hpp"

namespace liod {

class StateWriter;

/// The map frame's place: T_map_odom maps the odometry's poses into the backend's optimised map
/// (REP 105's map -> odom); `sequence` counts its changes (0: none yet, the identity).
struct MapCorrection {
  Eigen::Isometry3d map_from_odom = Eigen::Isometry3d::Identity();
  std::uint32_t sequence = 0;
  /// False while a saved map waits for the run to be placed in it (the map frame is then the
  /// run's own, flagged not_localized on the socket).
  bool localized = true;
};

struct BackendWorkerOptions {
  /// Called on the backend thread before each keyframe's work (its loop search and solve):
  /// tests make that work slow with it.
  std::function<void(const Keyframe&)> before_work;
};

class BackendWorker {
 public:
  explicit BackendWorker(const Config& config, BackendWorkerOptions options = {});
  ~BackendWorker();
  BackendWorker(const BackendWorker&) = delete;
  BackendWorker& operator=(const BackendWorker&) = delete;

  /// One keyframe, on the backend thread. Returns true when it closed a loop.
  bool process(const Keyframe& keyframe);
  /// End of the stream: the final state and the global map (map.pcd) when persisting.
  void finish();

  /// The latest correction (identity until a loop closes); any thread, without waiting for a solve.
  MapCorrection correction() const;
  /// The algorithm's state; read it only when the backend thread is not running (after join).
  const Backend& backend() const { return backend_; }
  /// Loops found/rejected and solve times, for the replay summary.
  std::string summary() const;

 private:
  void save_state();
  void publish_correction();
  void record_map_run();

  Config config_;
  BackendWorkerOptions options_;
  std::unique_ptr<StateWriter> writer_;
  Backend backend_;
  bool state_frozen_ = false;
  bool map_run_recorded_ = false;  // this run is in map_runs
  std::uint64_t published_version_ = 0;
  mutable std::mutex correction_mutex_;
  MapCorrection correction_;
};

}  // namespace liod
