#include "liod/drivers/rs_helios_msop.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "liod/angles.hpp"
#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/rs_helios_calibration.hpp"

namespace liod::drivers {
namespace {

using namespace helios;


[[nodiscard]] bool has_msop_magic(const std::uint8_t* p) noexcept {
  return std::equal(kMsopMagic.begin(), kMsopMagic.end(), p);
}

/// §2: rs_driver's little-endian temperature packing, 0.0625 °C per LSB.
[[nodiscard]] float decode_temperature(std::uint8_t b38, std::uint8_t b39) noexcept {
  const int lsb5 = b38 >> 3;
  const int msb7 = b39 & 0x7F;
  const int t = (msb7 << 5) + lsb5;
  return static_cast<float>((b39 & 0x80) != 0 ? -t : t) * 0.0625F;
}

[[nodiscard]] const std::uint8_t* block_at(const std::uint8_t* p, std::size_t b) noexcept {
  return p + kHeaderBytes + b * kBlockBytes;
}

const std::vector<std::array<float, 2>>& azimuth_trig() {
  static const std::vector<std::array<float, 2>> table = [] {
    std::vector<std::array<float, 2>> t(kFullCircle + 1);
    for (std::int32_t a = 0; a <= kFullCircle; ++a) {
      const double rad = a * 0.01 * kDegToRad;
      t[static_cast<std::size_t>(a)] = {static_cast<float>(std::cos(rad)), static_cast<float>(std::sin(rad))};
    }
    return t;
  }();
  return table;
}

/// cos/sin of `azimuth` (0.01° units), interpolated between the table's whole steps (error below 4e-9).
[[nodiscard]] std::array<float, 2> trig_at(std::span<const std::array<float, 2>> trig, float azimuth) noexcept {
  constexpr auto kTurn = static_cast<float>(kFullCircle);
  if (!(azimuth >= 0.0F && azimuth < kTurn)) {
    azimuth = std::fmod(azimuth, kTurn);
    if (azimuth < 0.0F) azimuth += kTurn;
    if (!(azimuth >= 0.0F && azimuth < kTurn)) azimuth = 0.0F;  // NaN
  }
  const auto whole = std::min(static_cast<std::int32_t>(azimuth), kFullCircle - 1);
  const float fraction = azimuth - static_cast<float>(whole);
  const auto& a = trig[static_cast<std::size_t>(whole)];
  const auto& b = trig[static_cast<std::size_t>(whole) + 1];
  return {a[0] + fraction * (b[0] - a[0]), a[1] + fraction * (b[1] - a[1])};
}

}  // namespace

MsopDecoder::MsopDecoder(HeliosModel model, MsopDecoderOptions options)
    : model_(model), options_(options), trig_(azimuth_trig()) {
  build_slot_tables();
  set_rotation_hz(kDefaultRotationHz);
}

void MsopDecoder::set_rotation_hz(double hz) noexcept {
  rotation_hz_ = (hz > 0.0 && std::isfinite(hz)) ? hz : kDefaultRotationHz;
  // §3.2: nominal block step round(36000 × rps × 55.56 µs), 20 at 10 Hz.
  nominal_step_ = static_cast<std::int32_t>(std::lround(kFullCircle * rotation_hz_ * kBlockPeriodS));
}

std::span<const std::uint16_t> MsopDecoder::rings() const noexcept {
  return {rings_.data(), beam_count(model_)};
}

void MsopDecoder::set_angles(std::span<const double> vertical_deg, std::span<const double> horizontal_deg) {
  const std::size_t lasers = beam_count(model_);
  if (vertical_deg.size() < lasers || horizontal_deg.size() < lasers)
    throw InputError("", 0,
                     "angle table has " + std::to_string(std::min(vertical_deg.size(), horizontal_deg.size())) +
                         " rows but the " + std::string(to_string(model_)) + " has " + std::to_string(lasers) +
                         " lasers");
  rings_by_elevation(vertical_deg.first(lasers), std::span<std::uint16_t>(rings_.data(), lasers));
  for (std::size_t i = 0; i < lasers; ++i) {
    const double el = vertical_deg[i] * kDegToRad;
    lasers_[i].cos_el = static_cast<float>(std::cos(el));
    lasers_[i].sin_el = static_cast<float>(std::sin(el));
    lasers_[i].horizontal_units = static_cast<float>(horizontal_deg[i] * 100.0);
  }
  has_angles_ = true;
}

void MsopDecoder::build_slot_tables() noexcept {
  constexpr float kBlockUs = static_cast<float>(kBlockPeriodS * 1e6);
  // §7: the 5515's dual-return table is the same set of offsets in ascending order.
  std::array<float, 32> sorted = kFiringOffsetsUs;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t s = 0; s < kSlotsPerBlock; ++s) {
    SlotEntry single;
    SlotEntry dual;
    if (model_ == HeliosModel::Helios16P) {
      // §8, with one correction from the real 16P data: in single return the two halves of a
      // block are two firings of the 16 lasers *within* one 55.56 µs block (firing offsets
      // 0..25.3 µs and 26.5..45.2 µs). The recording's DIFOP says "strongest" (single), its blocks
      // step 0.2° and its packets 666.7 µs apart; reading a block as 2 × 55.56 µs (rs_driver's
      // Rs16SingleReturnBlockIterator, as §8 describes) would contradict its own timestamps, and
      // nebula's reference clouds place slots 16..31 half a block later, as done here.
      single.laser = static_cast<std::uint8_t>(s % 16);
      single.time_s = kFiringOffsetsUs[s] * 1e-6F;
      single.az_fraction = kFiringOffsetsUs[s] / kBlockUs;
      // Dual: slots 16..31 are the second return of the same firing as slots 0..15.
      dual.laser = static_cast<std::uint8_t>(s % 16);
      dual.return_index = static_cast<std::uint8_t>(s / 16);
      dual.time_s = kFiringOffsetsUs[s % 16] * 1e-6F;
      dual.az_fraction = kFiringOffsetsUs[s % 16] / kBlockUs;
    } else {
      single.laser = static_cast<std::uint8_t>(s);
      single.time_s = kFiringOffsetsUs[s] * 1e-6F;
      single.az_fraction = kFiringOffsetsUs[s] / kBlockUs;
      dual.laser = static_cast<std::uint8_t>(s);
      dual.time_s = sorted[s] * 1e-6F;
      dual.az_fraction = sorted[s] / kBlockUs;
    }
    single_slots_[s] = single;
    dual_slots_[s] = dual;
  }
}

bool MsopDecoder::looks_dual_return(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != kPacketBytes) return false;
  const std::uint8_t* p = payload.data();
  for (std::size_t b = 0; b + 1 < kBlocksPerPacket; b += 2) {
    if (load_be16(block_at(p, b) + 2) != load_be16(block_at(p, b + 1) + 2)) return false;
  }
  return true;
}

MsopStatus MsopDecoder::decode(std::span<const std::uint8_t> payload, bool dual, std::int64_t arrival_ns,
                               PacketPoints& out, MsopHeader& header) const noexcept {
  out.block_count = 0;
  out.point_count = 0;
  if (payload.size() != kPacketBytes) return MsopStatus::WrongSize;
  const std::uint8_t* p = payload.data();
  if (!has_msop_magic(p)) return MsopStatus::BadMagic;

  header.protocol_version = load_be16(p + 4);
  header.top_counter = load_be32(p + 8);
  header.bottom_counter = load_be32(p + 12);
  header.range_resolution_flag = p[17];
  header.lidar_type = p[30];
  header.temperature_c = decode_temperature(p[38], p[39]);
  const std::uint64_t seconds = load_be48(p + 20);
  const std::uint32_t micros = load_be32(p + 26);
  if (micros >= 1'000'000 || seconds > kMaxTimestampSeconds) return MsopStatus::BadTimestamp;
  header.time_ns = static_cast<std::int64_t>(seconds) * 1'000'000'000LL + static_cast<std::int64_t>(micros) * 1000LL;
  // The arrival clock gets the same bound: a capture file's times are only what the file says, and
  // beyond it the packet and sweep time arithmetic would overflow.
  constexpr std::int64_t kMaxTimeNs = static_cast<std::int64_t>(kMaxTimestampSeconds) * 1'000'000'000LL;
  if (options_.time_source == TimeSource::ArrivalTime && (arrival_ns < 0 || arrival_ns > kMaxTimeNs))
    return MsopStatus::BadTimestamp;
  if (!has_angles_) return MsopStatus::NoCalibration;

  // §2.1: stop at the first block without its FF EE flag. The blocks before it carry their own
  // valid flags and are kept (as rs_driver does): UDP's checksum makes in-flight corruption
  // unlikely, so a bad flag means the sensor wrote a short packet, and its head is still good.
  std::size_t blocks = 0;
  std::array<std::int32_t, kBlocksPerPacket> az{};
  while (blocks < kBlocksPerPacket) {
    const std::uint8_t* b = block_at(p, blocks);
    if (b[0] != 0xFF || b[1] != 0xEE) break;
    az[blocks] = load_be16(b + 2);
    // A block azimuth outside 0..35999 means the packet is corrupt; refuse all of it.
    if (az[blocks] >= kFullCircle) return MsopStatus::BadAzimuth;
    ++blocks;
  }
  if (blocks == 0) return MsopStatus::BrokenFirstBlock;

  float meters_per_unit = 0.0025F;
  if (options_.range_resolution == RangeResolution::Fixed5mm ||
      (options_.range_resolution == RangeResolution::FromHeader && header.range_resolution_flag == 0))
    meters_per_unit = 0.005F;

  // The 5515 carries the two returns in block pairs (§7); the 16P inside each block (§8).
  const bool pairs = dual && model_ == HeliosModel::Helios5515;
  const std::size_t group = pairs ? 2 : 1;
  const double block_period = kBlockPeriodS;
  const double packet_duration = block_period * static_cast<double>(kBlocksPerPacket / group);
  out.time_ns = options_.time_source == TimeSource::SensorClock
                    ? header.time_ns
                    : arrival_ns - static_cast<std::int64_t>(std::llround(packet_duration * 1e9));

  // §3 / §3.2: block time offsets and azimuth steps to the next block (or pair).
  std::array<float, kBlocksPerPacket> block_time{};
  std::array<std::int32_t, kBlocksPerPacket> block_step{};
  double t = 0.0;
  for (std::size_t k = 0; k < blocks; k += group) {
    std::int32_t step = nominal_step_;
    double dt = block_period;
    const std::size_t next = k + group;
    if (next < blocks) {
      const std::int32_t diff = (az[next] - az[k] + kFullCircle) % kFullCircle;
      if (diff > kBlindZoneJump) {
        // Blind zone: nominal azimuth step for the points, and the time the motor takes to turn
        // through the jump for the next block. (rs_driver derives the same time from the DIFOP
        // FOV setting; using the jump itself needs no DIFOP and agrees when the FOV is right.)
        dt = diff / (kFullCircle * rotation_hz_);
      } else {
        step = diff;
      }
    }
    for (std::size_t g = 0; g < group && k + g < blocks; ++g) {
      block_time[k + g] = static_cast<float>(t);
      block_step[k + g] = step;
    }
    t += dt;
  }

  const std::array<SlotEntry, 32>& slots = dual ? dual_slots_ : single_slots_;
  const float min_range = options_.min_range_m;
  const float max_range = options_.max_range_m;
  const float rx = options_.lens_offset_m;
  std::size_t n = 0;
  for (std::size_t k = 0; k < blocks; ++k) {
    const std::uint8_t* b = block_at(p, k);
    const std::uint8_t* slot_bytes = b + 4;
    const std::uint8_t pair_return = pairs ? static_cast<std::uint8_t>(k & 1U) : 0;
    const float step = static_cast<float>(block_step[k]);
    const std::size_t first = n;
    for (std::size_t s = 0; s < kSlotsPerBlock; ++s, slot_bytes += kSlotBytes) {
      const std::uint16_t raw = load_be16(slot_bytes);
      if (raw == 0) continue;  // no return
      const float d = static_cast<float>(raw) * meters_per_unit;
      if (d < min_range || d > max_range) continue;
      const SlotEntry& se = slots[s];
      const LaserEntry& le = lasers_[se.laser];
      // §3.2: channel azimuth interpolated over the block step; §4: final = + horizontal offset. Not
      // rounded to 0.01° as rs_driver and nebula do: the laser fires where the head has turned to,
      // and a channel's rounding, the same every turn, turned its points by up to 0.005°: as much as
      // a unit's own beam angle errors, which the map relays into a heading drift (docs/design.md,
      // "Open problems").
      const float az_ch = static_cast<float>(az[k]) + step * se.az_fraction;
      const auto tf = trig_at(trig_, az_ch + le.horizontal_units);
      const auto tc = trig_at(trig_, az_ch);
      const float horizontal = d * le.cos_el;
      LidarPoint& pt = out.points[n++];
      // §4 (rs_driver): packet azimuth runs clockwise, hence -sin for a right-handed y-left frame.
      pt.x = horizontal * tf[0] + rx * tc[0];
      pt.y = -horizontal * tf[1] - rx * tc[1];
      pt.z = d * le.sin_el;
      pt.intensity = static_cast<float>(slot_bytes[2]);
      pt.time = block_time[k] + se.time_s;
      pt.ring = rings_[se.laser];
      pt.return_index = static_cast<std::uint8_t>(pair_return + se.return_index);
    }
    FiringBlock& fb = out.blocks[k];
    fb.azimuth = static_cast<std::uint16_t>(az[k]);
    fb.time_offset_s = block_time[k];
    fb.first_point = static_cast<std::uint16_t>(first);
    fb.point_count = static_cast<std::uint16_t>(n - first);
  }
  out.block_count = blocks;
  out.point_count = n;
  return blocks < kBlocksPerPacket ? MsopStatus::Partial : MsopStatus::Ok;
}

}  // namespace liod::drivers
