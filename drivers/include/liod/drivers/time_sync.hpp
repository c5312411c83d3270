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
// - ClockStepBridge: keeps one stream's time continuous through such a step (or a sensor that
//   re-synchronised), so that the odometry never integrates across a jump.
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

/// Takes the steps out of a stream's data clock. Each sample comes with its arrival time on the
/// monotonic clock, which never steps, and that tells a step from what else moves data time:
/// - forward: the data advanced by more than `threshold` beyond the arrival clock since the
///   previous sample (lost samples advance both clocks; a late delivery only the arrival clock);
/// - backward: the data time went back by more than `threshold` (nothing else does that).
/// Across a step the stream is taken to have kept its previous sample spacing, so a regular
/// stream comes out exactly as if nothing had happened; the correction then stays (liod's
/// timeline is the one it started on, until a restart) and later steps add to it.
/// The data must run at the arrival clock's pace (live, or a replay at recorded pace or faster
/// with no data gap longer than `threshold` times pace / (pace - 1)).
class ClockStepBridge {
 public:
  explicit ClockStepBridge(std::int64_t threshold_ns) : threshold_ns_(threshold_ns) {}
  /// The data time with every step so far taken out.
  std::int64_t correct(std::int64_t data_ns, std::int64_t arrival_ns) noexcept;
  std::int64_t correction_ns() const noexcept { return correction_ns_; }
  std::uint64_t steps() const noexcept { return steps_; }
  /// Size of the last step (data time moved by this much more than the stream's spacing).
  std::int64_t last_step_ns() const noexcept { return last_step_ns_; }

 private:
  std::int64_t threshold_ns_;
  bool have_previous_ = false;
  std::int64_t previous_data_ns_ = 0, previous_arrival_ns_ = 0;
  std::int64_t spacing_ns_ = -1;  // the last regular data interval, -1 until there is one
  std::int64_t correction_ns_ = 0;
  std::int64_t last_step_ns_ = 0;
  std::uint64_t steps_ = 0;
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
