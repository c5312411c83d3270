#pragma once
// Xsens MTi "MTData2" binary output (Xbus protocol), as sent on the serial line:
//
//   PRE 0xFA | BID 0xFF | MID 0x36 | LEN (1 byte; 0xFF = extended: 2 more bytes, big-endian) |
//   DATA: packets of [XDI 16-bit BE | size 8-bit | payload] | CS
//
// The message is valid when every byte after the preamble, checksum included, sums to 0 mod 256.
// All values are big-endian; the items used here (XDI low nibble 0x0 = float32):
//   0x1020 PacketCounter (u16), 0x1060 SampleTimeFine (u32, 10 kHz ticks),
//   0x8020 RateOfTurn (3 x f32, rad/s), 0x4020 Acceleration (3 x f32, m/s^2, specific force),
//   0x4030 FreeAcceleration (3 x f32, gravity removed: not usable as an IMU input, ignored),
//   0xE020 StatusWord (u32; bits 8-10 clipping of the accelerometer x, y, z, bits 11-13 of the
//   gyroscope x, y, z: Xsens MT SDK xsstatusflag.h, XSF_ClipAccX .. XSF_ClipGyrZ).
// Unknown items are skipped by their size. The parser is fed raw bytes in any chunking and
// resynchronises on the next preamble after garbage, a bad checksum or a truncated message.

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace liod::drivers::xsens {

inline constexpr std::uint8_t kPreamble = 0xFA;
inline constexpr std::uint8_t kBusId = 0xFF;
inline constexpr std::uint8_t kMidMtData2 = 0x36;
inline constexpr std::uint16_t kPacketCounter = 0x1020;
inline constexpr std::uint16_t kSampleTimeFine = 0x1060;
inline constexpr std::uint16_t kRateOfTurn = 0x8020;
inline constexpr std::uint16_t kAcceleration = 0x4020;
inline constexpr std::uint16_t kFreeAcceleration = 0x4030;
inline constexpr std::uint16_t kStatusWord = 0xE020;
inline constexpr std::uint32_t kClipAccX = 1U << 8;  ///< StatusWord: then y, z at bits 9, 10
inline constexpr std::uint32_t kClipGyrX = 1U << 11; ///< StatusWord: then y, z at bits 12, 13

/// Whether a StatusWord says the accelerometer / gyroscope axis (0..2) clipped in this sample.
[[nodiscard]] constexpr bool accel_clipped(std::uint32_t status_word, int axis) noexcept {
  return (status_word & (kClipAccX << axis)) != 0;
}
[[nodiscard]] constexpr bool gyro_clipped(std::uint32_t status_word, int axis) noexcept {
  return (status_word & (kClipGyrX << axis)) != 0;
}
/// Any accelerometer or gyroscope axis clipped (the magnetometer's flags are not liod's concern).
[[nodiscard]] constexpr bool inertial_clipped(std::uint32_t status_word) noexcept {
  return (status_word & (7U * kClipAccX | 7U * kClipGyrX)) != 0;
}

struct MtData2Sample {
  std::optional<std::uint16_t> packet_counter;
  std::optional<std::uint32_t> sample_time_fine;  ///< 10 kHz ticks
  std::optional<Eigen::Vector3d> rate_of_turn;    ///< rad/s
  std::optional<Eigen::Vector3d> acceleration;    ///< m/s^2 (specific force)
  std::optional<std::uint32_t> status_word;       ///< see accel_clipped / gyro_clipped
};

struct MtParserStats {
  std::uint64_t messages = 0;          ///< valid MTData2 messages
  std::uint64_t other_messages = 0;    ///< valid Xbus messages with another MID (acks, errors)
  std::uint64_t bad_checksum = 0;
  std::uint64_t malformed = 0;         ///< checksum fine but item sizes do not add up or a value is NaN/inf
  std::uint64_t skipped_bytes = 0;     ///< bytes discarded while looking for a preamble
  std::uint64_t counter_gaps = 0;      ///< samples missing per PacketCounter
};

class MtData2Parser {
 public:
  using Callback = std::function<void(const MtData2Sample&)>;
  explicit MtData2Parser(Callback on_sample) : on_sample_(std::move(on_sample)) {}
  /// Consumes bytes; calls back once per valid MTData2 message.
  void feed(std::span<const std::uint8_t> bytes);
  const MtParserStats& stats() const noexcept { return stats_; }

 private:
  void parse_buffer();
  bool decode_payload(std::span<const std::uint8_t> data, MtData2Sample& out) const;
  Callback on_sample_;
  std::vector<std::uint8_t> buffer_;
  MtParserStats stats_;
  std::optional<std::uint16_t> last_counter_;
};

/// Builds one MTData2 message (for tests and simulators): counter, fine time, gyro, accel.
/// An Xbus message (preamble, bus id, message id, length, data, checksum) around `data`.
std::vector<std::uint8_t> build_xbus_message(std::uint8_t mid, const std::vector<std::uint8_t>& data);
std::vector<std::uint8_t> build_mtdata2(std::uint16_t counter, std::uint32_t sample_time_fine,
                                        const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel,
                                        std::optional<std::uint32_t> status_word = std::nullopt);

}  // namespace liod::drivers::xsens
