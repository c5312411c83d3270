#include "liod/drivers/rs_helios.hpp"

#include <algorithm>
#include <span>
#include <utility>

#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

SweepOptions sweep_options(const HeliosOptions& o) {
  SweepOptions s;
  s.split_azimuth_deg = o.split_azimuth_deg;
  s.max_block_gap_s = o.max_block_gap_s;
  s.emit_partial_on_flush = o.emit_partial_sweep_on_flush;
  s.beam_count = beam_count(o.model);
  // One revolution at 10 Hz: 1800 firings of every laser, twice in dual return.
  s.reserve_points = std::size_t{1800} * 32 * 2;
  return s;
}

// A counter jump beyond this is a sensor restart or a different sensor, not loss.
constexpr std::uint32_t kMaxPlausibleLoss = 100000;

}  // namespace

bool is_helios_packet(std::span<const std::uint8_t> payload) noexcept {
  if (payload.size() != helios::kPacketBytes) return false;
  return has_difop_magic(payload) ||
         std::equal(helios::kMsopMagic.begin(), helios::kMsopMagic.end(), payload.begin());
}

RsHeliosDecoder::RsHeliosDecoder(HeliosOptions options, SweepCallback on_sweep)
    : options_(std::move(options)),
      msop_(options_.model, options_.msop),
      sweeps_(sweep_options(options_), std::move(on_sweep)) {
  if (options_.angles) {
    const std::size_t rows = options_.angles->size();
    if (rows != beam_count(options_.model))
      throw InputError("", 0,
                       "angle table has " + std::to_string(rows) + " rows, the " +
                           std::string(to_string(options_.model)) + " needs " +
                           std::to_string(beam_count(options_.model)) + " (wrong model or file?)");
    msop_.set_angles(options_.angles->vertical_deg, options_.angles->horizontal_deg);
  }
}

HeliosStats RsHeliosDecoder::stats() const noexcept {
  HeliosStats s = stats_;
  s.sweeps = sweeps_.sweeps_emitted();
  s.partial_sweeps_dropped = sweeps_.partial_sweeps_dropped();
  s.time_gaps = sweeps_.time_gaps();
  s.truncated_sweeps = sweeps_.truncated_sweeps();
  s.largest_sweep_points = sweeps_.largest_sweep_points();
  s.duplicate_packets = sweeps_.duplicate_packets();
  s.late_packets = sweeps_.late_packets();
  s.late_packets_dropped = sweeps_.late_packets_dropped();
  return s;
}

void RsHeliosDecoder::flush() { sweeps_.flush(); }

bool RsHeliosDecoder::packet_is_dual(std::span<const std::uint8_t> payload) const noexcept {
  switch (options_.return_mode) {
    case ReturnModePolicy::ForceSingle:
      return false;
    case ReturnModePolicy::ForceDual:
      return true;
    case ReturnModePolicy::Auto:
      break;
  }
  if (difop_) return difop_->dual_return();
  return options_.model == HeliosModel::Helios5515 && MsopDecoder::looks_dual_return(payload);
}

PacketKind RsHeliosDecoder::feed(std::span<const std::uint8_t> payload, std::int64_t arrival_ns) {
  if (has_difop_magic(payload)) {
    if (parse_difop(payload, scratch_difop_) != DifopStatus::Ok) {
      ++stats_.wrong_size;
      return PacketKind::Rejected;
    }
    on_difop(scratch_difop_);
    return PacketKind::Difop;
  }
  const bool dual = packet_is_dual(payload);
  const MsopStatus status = msop_.decode(payload, dual, arrival_ns, packet_, header_);
  switch (status) {
    case MsopStatus::Ok:
      break;
    case MsopStatus::Partial:
      ++stats_.broken_block_flag;
      break;
    case MsopStatus::WrongSize:
      ++stats_.wrong_size;
      return PacketKind::Rejected;
    case MsopStatus::BadMagic:
      ++stats_.bad_magic;
      return PacketKind::Rejected;
    case MsopStatus::BadTimestamp:
      ++stats_.bad_timestamp;
      return PacketKind::Rejected;
    case MsopStatus::BadAzimuth:
      ++stats_.bad_azimuth;
      return PacketKind::Rejected;
    case MsopStatus::BrokenFirstBlock:
      ++stats_.broken_first_block;
      return PacketKind::Rejected;
    case MsopStatus::NoCalibration:
      if (hold(payload, arrival_ns)) return PacketKind::Msop;
      ++stats_.no_calibration;
      return PacketKind::Rejected;
  }
  last_dual_ = dual;
  ++stats_.msop;
  stats_.points += packet_.point_count;
  if (options_.msop.range_resolution == RangeResolution::FromHeader && header_.range_resolution_flag > 1)
    ++stats_.unknown_range_flag;
  on_msop_header(header_);
  if (packet_.block_count > 0) {
    const std::uint16_t first = packet_.blocks[0].azimuth;
    if (have_azimuth_) {
      const int step = (first - last_azimuth_ + helios::kAzimuthUnits) % helios::kAzimuthUnits;
      if (step > helios::kBlindZoneJump) ++stats_.azimuth_jumps;
    }
    have_azimuth_ = true;
    last_azimuth_ = packet_.blocks[packet_.block_count - 1].azimuth;
  }
  sweeps_.add(packet_);
  return PacketKind::Msop;
}

void RsHeliosDecoder::on_msop_header(const MsopHeader& header) {
  // The bottom-board counter (+1 per packet, nebula's layout). A unit that leaves it at 0 gives no
  // evidence either way, so runs of zeros are not counted as loss.
  const std::uint32_t counter = header.bottom_counter;
  if (have_counter_ && !(counter == 0 && last_counter_ == 0)) {
    const std::uint32_t delta = counter - last_counter_;  // modulo 2^32: wrap-around is fine
    if (delta == 0 || delta > kMaxPlausibleLoss) {
      ++stats_.counter_resets;
    } else {
      stats_.lost_packets += delta - 1;
    }
  }
  have_counter_ = true;
  last_counter_ = counter;
}

void RsHeliosDecoder::on_difop(const HeliosDifop& difop) {
  ++stats_.difop;
  difop_ = difop;
  msop_.set_rotation_hz(difop.rotation_hz());
  if (!difop.angles_valid) {
    ++stats_.difop_angles_rejected;
  } else if (options_.use_difop_angles) {
    // The 16P's DIFOP carries 32 rows; its lasers are the first 16 (slot % 16, §8).
    msop_.set_angles(std::span<const double>(difop.angles.vertical_deg),
                     std::span<const double>(difop.angles.horizontal_deg));
  }
  decode_held();
}

bool RsHeliosDecoder::hold(std::span<const std::uint8_t> payload, std::int64_t arrival_ns) {
  // After a DIFOP, missing angles mean its table was unusable: waiting would not help.
  if (difop_ || held_.size() >= options_.max_held_packets) return false;
  held_.push_back({std::vector<std::uint8_t>(payload.begin(), payload.end()), arrival_ns});
  ++stats_.held_for_calibration;
  return true;
}

void RsHeliosDecoder::decode_held() {
  // Exactly as if they had come after this DIFOP (the order of a capture taken on one socket).
  std::vector<HeldPacket> held;
  held.swap(held_);
  for (const auto& p : held) feed(p.payload, p.arrival_ns);
}

}  // namespace liod::drivers
