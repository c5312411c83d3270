// Fuzz target: the RS-Helios stream decoder (DIFOP, MSOP, sweep assembly), fed the UDP payloads a
// socket or a capture file delivers.
//
// Input: a 10-byte prologue, then the payloads back to back, 1248 bytes each (the size of every
// MSOP and DIFOP packet); a shorter tail is fed as well, as the wrong-sized packet it is.
//   byte 0   bit 0: 16P (else 5515); bits 1-2: return-mode policy (3: auto, and a later DIFOP's
//            calibration followed at the next sweep boundary); bit 3: take DIFOP's angles;
//            bit 4: start with an angle table; bit 5: arrival-time clock; bits 6-7: range resolution
//   byte 1   bits 0-6: split azimuth in 360/128° steps; bit 7: emit the partial sweep on flush
//   2..9     arrival time of the first packet, ns, little-endian; then one packet per 2/3 ms
// Checked: every packet is counted once, and every point handed out is finite and well formed.

#include <cmath>
#include <cstdint>
#include <span>

#include "fuzz_support.hpp"
#include "liod/drivers/rs_helios.hpp"

namespace {

using namespace liod::drivers;

constexpr std::size_t kPrologue = 10;
constexpr std::uint64_t kPacketPeriodNs = 666'667;

AngleTable spread_angles(HeliosModel model) {
  AngleTable t;
  for (std::size_t i = 0; i < beam_count(model); ++i) {
    t.vertical_deg.push_back(-55.0 + 2.2 * static_cast<double>(i));
    t.horizontal_deg.push_back(i % 2 == 0 ? 4.0 : -4.0);
  }
  return t;
}

HeliosOptions options_from(const std::uint8_t* p) {
  HeliosOptions o;
  o.model = (p[0] & 1U) != 0 ? HeliosModel::Helios16P : HeliosModel::Helios5515;
  constexpr ReturnModePolicy kPolicies[] = {ReturnModePolicy::Auto, ReturnModePolicy::ForceSingle,
                                            ReturnModePolicy::ForceDual, ReturnModePolicy::Auto};
  o.return_mode = kPolicies[(p[0] >> 1) & 3U];
  o.calibration_updates = ((p[0] >> 1) & 3U) == 3 ? CalibrationUpdates::Follow : CalibrationUpdates::Pin;
  o.use_difop_angles = (p[0] & 8U) != 0;
  if ((p[0] & 16U) != 0) o.angles = spread_angles(o.model);
  o.msop.time_source = (p[0] & 32U) != 0 ? TimeSource::ArrivalTime : TimeSource::SensorClock;
  constexpr RangeResolution kResolutions[] = {RangeResolution::FromHeader, RangeResolution::Fixed2_5mm,
                                              RangeResolution::Fixed5mm, RangeResolution::FromHeader};
  o.msop.range_resolution = kResolutions[p[0] >> 6];
  o.split_azimuth_deg = (p[1] & 0x7FU) * (360.0 / 128.0);
  o.emit_partial_sweep_on_flush = (p[1] & 0x80U) != 0;
  return o;
}

void check_sweep(const liod::Scan& scan, HeliosModel model) {
  using liod::fuzz::require;
  require(scan.beam_count == beam_count(model), "sweep beam count differs from the model's");
  require(std::isfinite(scan.start_time) && std::isfinite(scan.end_time) && scan.start_time <= scan.end_time,
          "sweep start/end times not finite or out of order");
  for (const liod::LidarPoint& p : scan.points) {
    require(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(p.intensity),
            "point not finite");
    require(std::isfinite(p.time) && p.time >= 0.0F, "point time not finite or before the sweep start");
    require(p.ring < scan.beam_count, "ring beyond the beam count");
    require(p.return_index <= 1, "return index beyond the second return");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < kPrologue) return 0;
  const HeliosOptions options = options_from(data);
  std::uint64_t arrival = 0;
  for (int i = 7; i >= 0; --i) arrival = (arrival << 8) | data[2 + i];

  const HeliosModel model = options.model;
  RsHeliosDecoder decoder(options, [&](liod::Scan& scan, const SweepInfo&) { check_sweep(scan, model); });
  std::span<const std::uint8_t> packets(data + kPrologue, size - kPrologue);
  std::uint64_t fed = 0;
  while (!packets.empty()) {
    const std::size_t n = std::min(packets.size(), helios::kPacketBytes);
    decoder.feed(packets.first(n), static_cast<std::int64_t>(arrival));
    packets = packets.subspan(n);
    arrival += kPacketPeriodNs;  // unsigned: wraps like a clock field would, never undefined
    ++fed;
  }
  decoder.flush();
  const HeliosStats s = decoder.stats();
  liod::fuzz::require(s.msop + s.difop + s.rejected() == fed, "a packet was neither decoded nor counted as rejected");
  return 0;
}
