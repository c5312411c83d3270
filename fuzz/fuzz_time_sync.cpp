// Fuzz target: the time synchronisation (drivers/time_sync.hpp) fed any clock readings: the
// OffsetTracker (host - sensor offset of the LiDAR and the serial IMU), the ClockStepBridge (the
// steps taken out of a live stream's time) and the PPS edge correction. Their inputs are header
// times, capture times and SampleTimeFine counts from outside, so any int64 may reach them.
//
// Input: a 5-byte prologue, then 17-byte records.
//   byte 0      tracker window, 2^(b % 40) ns;   byte 1  jump threshold, 2^(b % 40) ns
//   byte 2      confirm count, 1 + b % 8;        byte 3  bridge threshold, 2^(b % 40) ns
//   byte 4      unused
//   record      1 byte: operation (b % 3: tracker add, bridge correct, PPS edge), then two
//               little-endian int64: (local, remote) / (data, arrival) / (edge, unused)
// Checked: no undefined behaviour (UBSan); add() returns offset_ns(); a jump or a step is counted
// at most once per reading; the bridge returns the data time plus its correction (held at the ends
// of the int64 range); a PPS correction is the whole second nearest the edge, within 0.4 s of it,
// or the "no edge" value.

#include <cstdint>
#include <cstring>
#include <limits>

#include "fuzz_support.hpp"
#include "liod/drivers/time_sync.hpp"

namespace {

std::int64_t int64_at(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  std::int64_t out = 0;
  std::memcpy(&out, &v, sizeof out);
  return out;
}

std::int64_t power_of_two_ns(std::uint8_t b) { return std::int64_t{1} << (b % 40); }

/// a + b held at the ends of the int64 range, as the time code keeps a wild reading.
std::int64_t held_sum(std::int64_t a, std::int64_t b) {
  std::int64_t r = 0;
  if (!__builtin_add_overflow(a, b, &r)) return r;
  return a < 0 ? std::numeric_limits<std::int64_t>::min() : std::numeric_limits<std::int64_t>::max();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  constexpr std::size_t kPrologue = 5;
  constexpr std::size_t kRecord = 17;
  if (size < kPrologue) return 0;
  liod::drivers::OffsetTracker tracker(power_of_two_ns(data[0]), power_of_two_ns(data[1]), 1 + data[2] % 8);
  liod::drivers::ClockStepBridge bridge(power_of_two_ns(data[3]));
  for (std::size_t pos = kPrologue; pos + kRecord <= size; pos += kRecord) {
    const std::uint8_t op = data[pos] % 3;
    const std::int64_t a = int64_at(data + pos + 1);
    const std::int64_t b = int64_at(data + pos + 9);
    if (op == 0) {
      const std::uint64_t jumps = tracker.jumps();
      require(tracker.add(a, b) == tracker.offset_ns(), "add() and offset_ns() disagree");
      require(tracker.valid(), "no offset after a reading");
      require(tracker.jumps() - jumps <= 1, "one reading counted as several jumps");
    } else if (op == 1) {
      const std::uint64_t steps = bridge.steps();
      const std::int64_t before = bridge.correction_ns();
      const std::int64_t out = bridge.correct(a, b);
      require(bridge.steps() - steps <= 1, "one reading counted as several steps");
      require(bridge.steps() != steps || bridge.correction_ns() == before, "the correction moved without a step");
      require(out == held_sum(a, bridge.correction_ns()), "the bridged time is not the data time plus the correction");
    } else {
      const std::int64_t c = liod::drivers::pps_edge_correction(a);
      if (c != std::numeric_limits<std::int64_t>::min()) {
        require(c >= -400'000'000 && c <= 400'000'000, "a PPS correction beyond 0.4 s");
        require((static_cast<__int128>(a) + c) % 1'000'000'000 == 0, "a PPS correction that does not land on a whole second");
      }
    }
  }
  return 0;
}
