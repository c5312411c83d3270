#include "liod/drivers/time_sync.hpp"

#include <gpiod.h>

#include <cerrno>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <limits>
#include <stdexcept>

namespace liod::drivers {
namespace {
std::int64_t clock_ns(clockid_t id) noexcept {
  timespec ts{};
  ::clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

// The readings come from outside (header times, capture times of a file, SampleTimeFine counts):
// any two int64 may meet here, and their sum or difference must stay defined. Held at the range's
// ends, a wild reading still reads as far off, with its sign.
std::int64_t saturating_sub(std::int64_t a, std::int64_t b) noexcept {
  std::int64_t r = 0;
  if (!__builtin_sub_overflow(a, b, &r)) return r;
  return a < 0 ? std::numeric_limits<std::int64_t>::min() : std::numeric_limits<std::int64_t>::max();
}

std::int64_t saturating_add(std::int64_t a, std::int64_t b) noexcept {
  std::int64_t r = 0;
  if (!__builtin_add_overflow(a, b, &r)) return r;
  return a < 0 ? std::numeric_limits<std::int64_t>::min() : std::numeric_limits<std::int64_t>::max();
}

/// |a - b|, exact for any two int64.
std::uint64_t distance(std::int64_t a, std::int64_t b) noexcept {
  const auto ua = static_cast<std::uint64_t>(a);
  const auto ub = static_cast<std::uint64_t>(b);
  return a >= b ? ua - ub : ub - ua;
}
}  // namespace

std::int64_t realtime_ns() noexcept { return clock_ns(CLOCK_REALTIME); }
std::int64_t monotonic_ns() noexcept { return clock_ns(CLOCK_MONOTONIC); }

std::int64_t OffsetTracker::add(std::int64_t local_ns, std::int64_t remote_ns) {
  const std::int64_t diff = saturating_sub(local_ns, remote_ns);
  if (!window_.empty() && distance(diff, window_.front().diff) > static_cast<std::uint64_t>(jump_ns_)) {
    // Either a delayed packet (only upwards, and bounded in practice) or a clock jump: a jump
    // shows on every following sample too.
    if (++outliers_ < confirm_) return offset_ns();
    ++jumps_;
    window_.clear();
  }
  outliers_ = 0;
  while (!window_.empty() && window_.back().diff >= diff) window_.pop_back();
  window_.push_back({local_ns, diff});
  while (window_.size() > 1 && window_.front().local < saturating_sub(local_ns, window_ns_)) window_.pop_front();
  return window_.front().diff;
}

ClockJumpDetector::ClockJumpDetector(std::int64_t threshold_ns)
    : threshold_ns_(threshold_ns), base_(realtime_ns() - monotonic_ns()) {}

std::int64_t ClockJumpDetector::check() noexcept {
  const std::int64_t now = realtime_ns() - monotonic_ns();
  const std::int64_t step = now - base_;
  base_ = now;  // slewing (ppm) accumulates slowly and is absorbed here call by call
  if (std::llabs(step) > threshold_ns_) {
    ++jumps_;
    return step;
  }
  return 0;
}

std::int64_t ClockStepBridge::correct(std::int64_t data_ns, std::int64_t arrival_ns) noexcept {
  if (have_previous_) {
    const std::int64_t data_dt = saturating_sub(data_ns, previous_data_ns_);
    const std::int64_t arrival_dt = saturating_sub(arrival_ns, previous_arrival_ns_);
    if (saturating_sub(data_dt, arrival_dt) > threshold_ns_ || data_dt < -threshold_ns_) {
      const std::int64_t kept = spacing_ns_ >= 0 ? spacing_ns_ : std::max<std::int64_t>(arrival_dt, 0);
      last_step_ns_ = saturating_sub(data_dt, kept);
      correction_ns_ = saturating_sub(correction_ns_, last_step_ns_);
      ++steps_;
    } else if (data_dt >= 0 && data_dt <= threshold_ns_) {
      spacing_ns_ = data_dt;
    }
  }
  have_previous_ = true;
  previous_data_ns_ = data_ns;
  previous_arrival_ns_ = arrival_ns;
  return saturating_add(data_ns, correction_ns_);
}

std::int64_t pps_edge_correction(std::int64_t edge_ns) noexcept {
  constexpr std::int64_t kSecond = 1000000000;
  // From the edge's place within its second, not from the edge plus half a second (that sum
  // overflows near the end of the range).
  std::int64_t into_second = edge_ns % kSecond;
  if (into_second < 0) into_second += kSecond;
  const std::int64_t c = into_second < kSecond / 2 ? -into_second : kSecond - into_second;
  return std::llabs(c) > 4 * kSecond / 10 ? std::numeric_limits<std::int64_t>::min() : c;
}

PpsDiscipline::PpsDiscipline(const std::string& chip, int line) {
  auto* c = ::gpiod_chip_open_by_name(chip.c_str());
  if (c == nullptr) throw std::runtime_error("PPS: cannot open GPIO chip '" + chip + "': " + std::strerror(errno));
  auto* l = ::gpiod_chip_get_line(c, static_cast<unsigned>(line));
  if (l == nullptr || ::gpiod_line_request_rising_edge_events(l, "liod-pps") != 0) {
    const std::string why = std::strerror(errno);
    ::gpiod_chip_close(c);
    throw std::runtime_error("PPS: cannot request rising edges on " + chip + " line " + std::to_string(line) + ": " + why);
  }
  chip_ = c;
  line_ = l;
  thread_ = std::thread([this] { run(); });
}

PpsDiscipline::~PpsDiscipline() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  ::gpiod_line_release(static_cast<gpiod_line*>(line_));
  ::gpiod_chip_close(static_cast<gpiod_chip*>(chip_));
}

void PpsDiscipline::run() {
  auto* line = static_cast<gpiod_line*>(line_);
  const timespec timeout{0, 200000000};  // bounded wait: the stop flag is checked 5x a second
  while (!stop_.load()) {
    if (::gpiod_line_event_wait(line, &timeout) != 1) continue;
    gpiod_line_event ev{};
    if (::gpiod_line_event_read(line, &ev) != 0) continue;
    // The event carries a kernel timestamp; older kernels use CLOCK_REALTIME, 5.7+ CLOCK_MONOTONIC.
    // Re-stamp on the realtime clock with the (small) delay since the edge measured on the same
    // clock the event used, whichever it is.
    const std::int64_t ev_ns = static_cast<std::int64_t>(ev.ts.tv_sec) * 1000000000 + ev.ts.tv_nsec;
    const std::int64_t mono = monotonic_ns();
    const std::int64_t real = realtime_ns();
    const std::int64_t age = std::llabs(mono - ev_ns) < std::llabs(real - ev_ns) ? mono - ev_ns : real - ev_ns;
    const std::int64_t edge = real - age;
    const std::int64_t c = pps_edge_correction(edge);
    if (c == std::numeric_limits<std::int64_t>::min()) continue;
    // Light smoothing: the edge jitter (interrupt latency, tens of µs) averages out over ~8 s.
    const std::int64_t prev = correction_.load();
    correction_.store(pulses_.load() == 0 ? c : prev + (c - prev) / 8);
    last_edge_.store(edge);
    pulses_.fetch_add(1);
  }
}

}  // namespace liod::drivers
