#pragma once
// RS-Helios DIFOP (device info) packet: motor speed, FOV, return mode, time sync, serial number
// and the per-channel angle calibration (spec §6).

#include <array>
#include <cstdint>
#include <span>

namespace liod::drivers {

/// The 32-row calibration carried in DIFOP, in packet channel order.
struct DifopAngles {
  std::array<double, 32> vertical_deg{};
  std::array<double, 32> horizontal_deg{};
};

struct HeliosDifop {
  std::uint16_t motor_rpm = 0;  ///< 600 = 10 Hz
  std::uint32_t lidar_ip = 0;   ///< host order
  std::uint32_t dest_ip = 0;
  std::array<std::uint8_t, 6> mac{};
  std::uint16_t msop_port = 0;
  std::uint16_t difop_port = 0;
  std::uint16_t fov_start = 0;  ///< 0.01°
  std::uint16_t fov_end = 0;    ///< 0.01°
  std::uint16_t phase_lock_angle = 0;
  std::array<std::uint8_t, 5> top_firmware{};
  std::array<std::uint8_t, 5> bottom_firmware{};
  std::array<std::uint8_t, 5> bottom_software{};
  std::array<std::uint8_t, 5> motor_firmware{};
  std::array<std::uint8_t, 3> hardware_version{};
  std::array<std::uint8_t, 6> serial_number{};
  std::uint16_t zero_angle_calibration = 0;
  std::uint8_t return_mode = 0;       ///< raw byte; see helios::kReturn*
  std::uint8_t time_sync_mode = 0;    ///< 0 GPS, 1 PTP E2E, 2 PTP P2P, 3 gPTP (nebula)
  std::uint8_t time_sync_status = 0;  ///< 0 invalid, 1 GPS ok, 2 PTP ok
  std::int64_t time_ns = 0;           ///< DIFOP's own UTC timestamp; 0 if the field is corrupt
  std::uint16_t real_rpm = 0;         ///< measured motor speed (diagnostics, offset 352)

  /// Valid only when `angles_valid`; otherwise `angles_rejected_reason` says why (spec §6 rules).
  DifopAngles angles;
  bool angles_valid = false;
  const char* angles_rejected_reason = "";

  [[nodiscard]] bool dual_return() const noexcept { return return_mode == 0x00; }
  /// Rotation rate; rs_driver falls back to 10 Hz when the rpm field reads 0.
  [[nodiscard]] double rotation_hz() const noexcept { return motor_rpm == 0 ? 10.0 : motor_rpm / 60.0; }
  /// Width of the blind (not reported) sector, 0.01°: 36000 − (end − start, wrapped).
  [[nodiscard]] std::uint16_t blind_zone() const noexcept;
};

enum class DifopStatus : std::uint8_t { Ok, WrongSize, BadMagic };

/// Parses a 1248-byte DIFOP payload. A rejected angle table does not fail the parse (the rest of
/// the packet is still good); it leaves `angles_valid` false.
[[nodiscard]] DifopStatus parse_difop(std::span<const std::uint8_t> payload, HeliosDifop& out) noexcept;

/// Decodes one 3-byte calibration angle (spec §6): byte 0 is the sign (0x00 positive, anything
/// else negative), bytes 1..2 a big-endian magnitude in 0.01°. Returns degrees.
[[nodiscard]] double decode_calibration_angle(const std::uint8_t* three_bytes) noexcept;

/// True when `payload` starts with the DIFOP magic (whatever its size).
[[nodiscard]] bool has_difop_magic(std::span<const std::uint8_t> payload) noexcept;

}  // namespace liod::drivers
