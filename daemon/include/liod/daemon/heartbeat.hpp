#pragma once
// What the watchdog knows of a thread: when it last showed progress, and, for a thread whose one
// unit of work can legitimately take long (the backend: a keyframe's loop checks, pose-graph
// solve and state files), since when it has been inside the current unit.
//
// A heartbeat means "this thread is not stuck". A loop that waits at most 100 ms beats every
// pass, so 2 s without a beat means stuck. The backend's unit of work is different: its loop
// check and solve run inside the core (no way to report progress or to abandon them half way)
// and take from milliseconds to seconds depending on the place and the machine's load. So while
// it is inside a unit, it counts as alive up to threads.backend_work_limit_s (60 s, twenty times
// the longest ever measured, docs/robustness.md): a slow backend sheds keyframes instead
// (Pipeline::backend_thread), while a hung one still gets the daemon restarted.

#include <atomic>
#include <cstdint>

namespace liod {

class Heartbeat {
 public:
  /// Progress outside a unit of work (a loop pass, a finished unit).
  void beat(std::int64_t now_ns) noexcept { beat_ns_.store(now_ns, std::memory_order_relaxed); }
  /// A unit of work that may take long starts / ends (the end is progress).
  void begin_work(std::int64_t now_ns) noexcept {
    beat(now_ns);
    busy_since_ns_.store(now_ns, std::memory_order_release);
  }
  void end_work(std::int64_t now_ns) noexcept {
    beat(now_ns);
    busy_since_ns_.store(0, std::memory_order_release);  // after the beat: a reader that sees 0 sees it
  }

  /// Stuck: inside a unit of work for longer than `work_limit_ns`, or else no beat for longer
  /// than `beat_limit_ns`.
  bool stalled(std::int64_t now_ns, std::int64_t beat_limit_ns, std::int64_t work_limit_ns) const noexcept {
    const std::int64_t busy_since = busy_since_ns_.load(std::memory_order_acquire);
    if (busy_since != 0) return now_ns - busy_since > work_limit_ns;
    return now_ns - beat_ns_.load(std::memory_order_relaxed) > beat_limit_ns;
  }
  /// How long the current unit of work has run (0 when idle), for health.
  double busy_s(std::int64_t now_ns) const noexcept {
    const std::int64_t busy_since = busy_since_ns_.load(std::memory_order_relaxed);
    return busy_since == 0 ? 0.0 : static_cast<double>(now_ns - busy_since) * 1e-9;
  }

 private:
  std::atomic<std::int64_t> beat_ns_{0};
  std::atomic<std::int64_t> busy_since_ns_{0};
};

}  // namespace liod
