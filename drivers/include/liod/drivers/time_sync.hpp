#pragma once
// One clock for everything (the host's CLOCK_REALTIME, Unix epoch, which PTP/GPS/NTP discipline
// on the vehicle). Pieces:
//
// - OffsetTracker: the offset between two clocks from (local, remote) timestamp pairs whose
//   difference is offset + a positive, jittery transport delay. The minimum of the differences
//   over a sliding window is the offset plus the smallest delay (robust to queueing and
//   scheduling delays, which only ever add). A step larger than the jump threshold, seen on
//   `confirm` consecutive samples, is a clock jump: the window restarts from the new level.
// - ClockJumpDetector: watches CLOCK_REALTIME against CLOCK_MONOTONIC (which never jumps) and
//   reports steps of the host clock (settimeofday, NTP step).
// - PpsDiscipline: a pulse-per-second on a GPIO line (libgpiod v1.6 API) marks the start of each
//   UTC second; the host time of the edge tells the host clock's error, which corrects the
//   host-stamped IMU samples.

#include <atomic>
#include <cstdint>
#include <deque>
#include <string>
#include <thread>

namespace liod::drivers {

std::int64_t realtime_ns() noexcept;
std::int64_t monotonic_ns() noexcept;

class OffsetTracker {
 public:
  OffsetTracker(std::int64_t window_ns, std::int64_t jump_threshold_ns, int confirm = 3)
      : window_ns_(window_ns), jump_ns_(jump_threshold_ns), confirm_(confirm) {}
  /// Adds a pair; `local_ns` drives the window. Returns the current offset (local - remote).
  std::int64_t add(std::int64_t local_ns, std::int64_t remote_ns);
  bool valid() const noexcept { return !window_.empty(); }
  std::int64_t offset_ns() const noexcept { return window_.empty() ? 0 : window_.front().diff; }
  std::uint64_t jumps() const noexcept { return jumps_; }
  void reset() noexcept {
    window_.clear();
    outliers_ = 0;
  }

 private:
  struct Entry {
    std::int64_t local;
    std::int64_t diff;
  };
  std::int64_t window_ns_;
  std::int64_t jump_ns_;
  int confirm_;
  std::deque<Entry> window_;  // monotonic deque: front is the minimum of the window
  int outliers_ = 0;
  std::uint64_t jumps_ = 0;
};

class ClockJumpDetector {
 public:
  explicit ClockJumpDetector(std::int64_t threshold_ns);
  /// Returns the step (ns) when the realtime clock jumped since the last call, else 0.
  std::int64_t check() noexcept;
  std::uint64_t jumps() const noexcept { return jumps_; }

 private:
  std::int64_t threshold_ns_;
  std::int64_t base_;
  std::uint64_t jumps_ = 0;
};

/// Watches PPS edges in its own thread. correction_ns() is what to add to a host time to get
/// UTC (0 until the first plausible edge). Throws std::runtime_error when the line cannot be
/// requested.
class PpsDiscipline {
 public:
  PpsDiscipline(const std::string& chip, int line);
  ~PpsDiscipline();
  PpsDiscipline(const PpsDiscipline&) = delete;
  PpsDiscipline& operator=(const PpsDiscipline&) = delete;
  std::int64_t correction_ns() const noexcept { return correction_.load(std::memory_order_relaxed); }
  std::uint64_t pulses() const noexcept { return pulses_.load(std::memory_order_relaxed); }
  std::int64_t last_edge_ns() const noexcept { return last_edge_.load(std::memory_order_relaxed); }

 private:
  void run();
  void* chip_ = nullptr;
  void* line_ = nullptr;
  std::atomic<bool> stop_{false};
  std::atomic<std::int64_t> correction_{0};
  std::atomic<std::uint64_t> pulses_{0};
  std::atomic<std::int64_t> last_edge_{0};
  std::thread thread_;
};

/// The correction for one PPS edge seen at host time `edge_ns`: the nearest whole second minus
/// the edge time; nullopt-like INT64_MIN when the edge is more than 0.4 s from a second (noise).
std::int64_t pps_edge_correction(std::int64_t edge_ns) noexcept;

}  // namespace liod::drivers
