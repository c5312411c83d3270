// Fuzz target: the CAN IMU decoders (J1939 profile, from any source and from one address, and a
// signal table of every width, sign and byte order), fed what a SocketCAN socket reads.
//
// Input: records of 18 bytes: a Linux `struct can_frame` (16 bytes, flags in the identifier, any
// length byte) and the little-endian µs since the previous frame. Checked: every sample finite.

#include <linux/can.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

#include "fuzz_support.hpp"
#include "liod/drivers/can_imu.hpp"

namespace {

using liod::drivers::CanImuDecoder;

constexpr std::size_t kRecord = sizeof(can_frame) + 2;
constexpr std::int64_t kStartNs = 1'700'000'000'000'000'000;
constexpr double kMaxPairAgeS = 1.5 / 200.0;  // the daemon's choice at a 200 Hz IMU

liod::CanSignalConfig table_signal(const char* quantity, std::uint32_t id, int byte, int bytes, bool big_endian,
                             bool is_signed, double scale) {
  liod::CanSignalConfig s;
  s.quantity = quantity;
  s.can_id = id;
  s.id_mask = 0x7FF;
  s.byte_offset = byte;
  s.length_bytes = bytes;
  s.big_endian = big_endian;
  s.is_signed = is_signed;
  s.scale = scale;
  s.offset = -1.0;
  return s;
}

/// One signal per quantity, over two identifiers, covering 1/2/4-byte, signed and big-endian
/// fields and an offset past the 8 data bytes (allowed by the config, never present in a frame).
std::vector<liod::CanSignalConfig> table() {
  return {table_signal("gyro_x", 0x100, 0, 2, false, true, 1e-3),   table_signal("gyro_y", 0x100, 2, 2, true, true, 1e-3),
          table_signal("gyro_z", 0x100, 4, 4, true, false, 1e-6),  table_signal("accel_x", 0x101, 0, 1, false, true, 0.1),
          table_signal("accel_y", 0x101, 1, 4, false, true, 1e-6), table_signal("accel_z", 0x101, 63, 1, false, false, 0.1)};
}

void check(const std::optional<liod::ImuSample>& s) {
  if (!s) return;
  liod::fuzz::require(std::isfinite(s->time) && s->gyro.allFinite() && s->accel.allFinite(), "non-finite IMU sample");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  CanImuDecoder any_source(liod::CanProfile::kJ1939, -1, {}, kMaxPairAgeS);
  CanImuDecoder one_source(liod::CanProfile::kJ1939, 0x80, {}, kMaxPairAgeS);
  CanImuDecoder by_table(liod::CanProfile::kTable, -1, table(), kMaxPairAgeS);
  std::int64_t time_ns = kStartNs;
  for (std::size_t pos = 0; pos + kRecord <= size; pos += kRecord) {
    can_frame raw{};
    std::memcpy(&raw, data + pos, sizeof raw);
    time_ns += 1000 * std::int64_t{data[pos + sizeof raw] | (data[pos + sizeof raw + 1] << 8)};
    const liod::drivers::CanFrame frame = liod::drivers::from_socketcan(raw, time_ns);
    check(any_source.feed(frame));
    check(one_source.feed(frame));
    check(by_table.feed(frame));
  }
  return 0;
}
