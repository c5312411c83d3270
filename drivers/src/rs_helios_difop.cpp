#include "liod/drivers/rs_helios_difop.hpp"

#include <algorithm>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/rs_helios_model.hpp"

namespace liod::drivers {
namespace {

// Field offsets, spec §6.
constexpr std::size_t kMotorRpm = 8;
constexpr std::size_t kEthernet = 10;
constexpr std::size_t kFov = 32;
constexpr std::size_t kPhaseLock = 38;
constexpr std::size_t kVersions = 40;
constexpr std::size_t kSerial = 292;
constexpr std::size_t kZeroAngle = 298;
constexpr std::size_t kReturnMode = 300;
constexpr std::size_t kSyncMode = 301;
constexpr std::size_t kSyncStatus = 302;
constexpr std::size_t kTime = 303;
constexpr std::size_t kRealRpm = 352;
constexpr std::size_t kVertAngles = 468;
constexpr std::size_t kHorizAngles = 564;

template <std::size_t N>
void copy_bytes(const std::uint8_t* p, std::array<std::uint8_t, N>& out) {
  std::copy(p, p + N, out.begin());
}

/// rs_driver's table checks (spec §6): an unprogrammed unit has 0xFF sign bytes; any value outside
/// [-90°, 180°) means the table is garbage. Either way the whole table is refused, never half-used.
void decode_angles(const std::uint8_t* p, HeliosDifop& out) {
  out.angles_valid = false;
  for (std::size_t ch = 0; ch < 32; ++ch) {
    const std::uint8_t* v = p + kVertAngles + ch * 3;
    const std::uint8_t* h = p + kHorizAngles + ch * 3;
    if (v[0] == 0xFF || h[0] == 0xFF) {
      out.angles_rejected_reason = "a sign byte is 0xFF (unprogrammed calibration)";
      return;
    }
    const double vert = decode_calibration_angle(v);
    const double horiz = decode_calibration_angle(h);
    if (vert < -90.0 || vert >= 180.0 || horiz < -90.0 || horiz >= 180.0) {
      out.angles_rejected_reason = "an angle lies outside [-90, 180) degrees";
      return;
    }
    out.angles.vertical_deg[ch] = vert;
    out.angles.horizontal_deg[ch] = horiz;
  }
  out.angles_valid = true;
  out.angles_rejected_reason = "";
}

}  // namespace

std::uint16_t HeliosDifop::blind_zone() const noexcept {
  const int span = (static_cast<int>(fov_end) - static_cast<int>(fov_start) + 36000) % 36000;
  // start == end (or 0..36000) means a full circle of view.
  if (span == 0) return 0;
  return static_cast<std::uint16_t>(36000 - span);
}

double decode_calibration_angle(const std::uint8_t* three_bytes) noexcept {
  const double magnitude = load_be16(three_bytes + 1) * 0.01;
  return three_bytes[0] == 0x00 ? magnitude : -magnitude;
}

bool has_difop_magic(std::span<const std::uint8_t> payload) noexcept {
  return payload.size() >= helios::kDifopMagic.size() &&
         std::equal(helios::kDifopMagic.begin(), helios::kDifopMagic.end(), payload.begin());
}

DifopStatus parse_difop(std::span<const std::uint8_t> payload, HeliosDifop& out) noexcept {
  if (payload.size() != helios::kPacketBytes) return DifopStatus::WrongSize;
  if (!has_difop_magic(payload)) return DifopStatus::BadMagic;
  const std::uint8_t* p = payload.data();
  out.motor_rpm = load_be16(p + kMotorRpm);
  out.lidar_ip = load_be32(p + kEthernet);
  out.dest_ip = load_be32(p + kEthernet + 4);
  copy_bytes(p + kEthernet + 8, out.mac);
  out.msop_port = load_be16(p + kEthernet + 14);
  out.difop_port = load_be16(p + kEthernet + 18);
  out.fov_start = load_be16(p + kFov);
  out.fov_end = load_be16(p + kFov + 2);
  out.phase_lock_angle = load_be16(p + kPhaseLock);
  copy_bytes(p + kVersions, out.top_firmware);
  copy_bytes(p + kVersions + 5, out.bottom_firmware);
  copy_bytes(p + kVersions + 10, out.bottom_software);
  copy_bytes(p + kVersions + 15, out.motor_firmware);
  copy_bytes(p + kVersions + 20, out.hardware_version);
  copy_bytes(p + kSerial, out.serial_number);
  out.zero_angle_calibration = load_be16(p + kZeroAngle);
  out.return_mode = p[kReturnMode];
  out.time_sync_mode = p[kSyncMode];
  out.time_sync_status = p[kSyncStatus];
  const std::uint64_t seconds = load_be48(p + kTime);
  const std::uint32_t micros = load_be32(p + kTime + 6);
  // 0 = "no usable time" (a corrupt field would overflow the nanosecond count).
  out.time_ns = (seconds <= helios::kMaxTimestampSeconds && micros < 1'000'000)
                    ? static_cast<std::int64_t>(seconds) * 1'000'000'000LL + static_cast<std::int64_t>(micros) * 1000LL
                    : 0;
  out.real_rpm = load_be16(p + kRealRpm);
  decode_angles(p, out);
  return DifopStatus::Ok;
}

}  // namespace liod::drivers
