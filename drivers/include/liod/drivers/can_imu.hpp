#pragma once
// IMU samples from CAN frames: the SAE J1939 default profile and a configurable signal table.
//
// J1939 profile (29-bit identifiers, PGN = bits 8..25, little-endian 16-bit SPNs):
//   PGN 61482 (0xF02A) Angular Rate Information: bytes 0-1 pitch rate, 2-3 roll rate, 4-5 yaw
//     rate; 1/128 deg/s per bit, offset -250 deg/s (raw 32000 = 0).
//   PGN 61485 (0xF02D) Acceleration Sensor: bytes 0-1 lateral, 2-3 longitudinal, 4-5 vertical;
//     0.01 m/s^2 per bit, offset -320 m/s^2 (raw 32000 = 0).
//   Raw values >= 0xFB00 mean "error" / "not available" (J1939-71) and reject the frame.
// Axes: x = longitudinal / roll axis, y = lateral / pitch axis, z = vertical / yaw axis, as the
// sensor reports them; a mounting that differs is expressed with the `table` profile (per-axis
// scale sign) or in extrinsics.
//
// A sample is emitted when an angular-rate frame arrives and an acceleration frame arrived less
// than `max_pair_age_s` before it (sensors send both at the same rate, the pair is one sample).
// Table profile: one signal per quantity; a sample is emitted on the frame carrying gyro_x, when
// every quantity arrived within `max_pair_age_s` before it: an axis whose frames stopped (or never
// came) would otherwise be read as its last value, or 0, as if measured.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "liod/drivers/sensor_config.hpp"
#include "liod/types.hpp"

struct can_frame;  // <linux/can.h>

namespace liod::drivers {

struct CanFrame {
  std::uint32_t id = 0;      ///< without the EFF/RTR/ERR flag bits
  bool extended = false;
  std::uint8_t dlc = 0;
  std::array<std::uint8_t, 8> data{};
  std::int64_t time_ns = 0;  ///< host receive time
};

struct CanImuStats {
  std::uint64_t frames = 0;
  std::uint64_t rate_frames = 0;
  std::uint64_t accel_frames = 0;
  std::uint64_t not_available = 0;   ///< frames with an error / not-available value
  std::uint64_t unpaired = 0;        ///< rate frames without a recent acceleration frame
  std::uint64_t stale_axes = 0;      ///< table: gyro_x frames without a recent value of every other quantity
  std::uint64_t samples = 0;
};

class CanImuDecoder {
 public:
  CanImuDecoder(CanProfile profile, int j1939_source_address, std::vector<CanSignalConfig> table,
                double max_pair_age_s = 0.02);
  /// Returns a sample when this frame completes one.
  std::optional<ImuSample> feed(const CanFrame& frame);
  const CanImuStats& stats() const noexcept { return stats_; }

  static constexpr std::uint32_t kPgnAngularRate = 61482;
  static constexpr std::uint32_t kPgnAcceleration = 61485;
  /// PGN of a 29-bit J1939 identifier (PDU1 frames carry a destination in PS, not part of the PGN).
  static std::uint32_t pgn(std::uint32_t id) noexcept;

 private:
  std::optional<ImuSample> feed_j1939(const CanFrame& f);
  std::optional<ImuSample> feed_table(const CanFrame& f);

  CanProfile profile_;
  int source_address_;
  std::vector<CanSignalConfig> table_;
  std::int64_t max_pair_age_ns_;
  CanImuStats stats_;
  Eigen::Vector3d accel_ = Eigen::Vector3d::Zero();
  std::int64_t accel_time_ns_ = 0;
  bool have_accel_ = false;
  std::array<double, 6> values_{};  // table profile: latest value per quantity...
  std::array<std::int64_t, 6> value_times_ns_{};  // ...the time of its frame...
  std::array<bool, 6> received_{};                 // ...and whether one came at all
};

/// A frame as SocketCAN delivers it, received at `time_ns`: the EFF/RTR/ERR flags split off the
/// identifier, the length clamped to the 8 data bytes of a classic frame.
CanFrame from_socketcan(const can_frame& raw, std::int64_t time_ns) noexcept;

/// Builds J1939 frames (for tests and simulators).
CanFrame make_j1939_rate_frame(const Eigen::Vector3d& rate_rad_s, std::uint8_t source_address, std::int64_t time_ns);
CanFrame make_j1939_accel_frame(const Eigen::Vector3d& accel_m_s2, std::uint8_t source_address, std::int64_t time_ns);

/// A SocketCAN raw socket on `interface` with kernel receive timestamps. Throws on failure.
class SocketCan {
 public:
  explicit SocketCan(const std::string& interface);
  ~SocketCan();
  SocketCan(const SocketCan&) = delete;
  SocketCan& operator=(const SocketCan&) = delete;
  /// Waits up to `timeout_ms`; false on timeout.
  bool read(CanFrame& frame, int timeout_ms);
  void write(const CanFrame& frame);

 private:
  int fd_ = -1;
};

}  // namespace liod::drivers
