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
      on_sweep_(std::move(on_sweep)),
      msop_(options_.model, options_.msop),
      sweeps_(sweep_options(options_), [this](Scan& scan, const SweepInfo& info) { on_assembled(scan, info); }) {
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
  if (applied_) return applied_->return_mode == helios::kReturnDual;
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
  add_to_sweeps(payload, arrival_ns);
  return PacketKind::Msop;
}

void RsHeliosDecoder::add_to_sweeps(std::span<const std::uint8_t> payload, std::int64_t arrival_ns) {
  const std::size_t boundary = pending_ ? sweeps_.next_sweep_block(packet_) : packet_.block_count;
  if (boundary >= packet_.block_count) {
    sweeps_.add(packet_);
    return;
  }
  sweeps_.add_blocks(packet_, 0, boundary);
  apply_pending(sweeps_.sweep_open());
  // The blocks from the boundary on begin the next sweep: decoded again, with its calibration.
  last_dual_ = packet_is_dual(payload);
  const MsopStatus again = msop_.decode(payload, last_dual_, arrival_ns, packet_, header_);
  if (again != MsopStatus::Ok && again != MsopStatus::Partial) return;
  if (boundary == 0) sweeps_.add(packet_);
  else sweeps_.add_blocks(packet_, boundary, packet_.block_count);
}

void RsHeliosDecoder::on_assembled(Scan& scan, const SweepInfo& info) {
  SweepInfo flagged = info;
  flagged.calibration_changed = flag_open_sweep_;
  flag_open_sweep_ = disagrees_ || changed_at_next_start_;
  changed_at_next_start_ = false;
  on_sweep_(scan, flagged);
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

bool RsHeliosDecoder::Calibration::differs_from(const Calibration& in_use) const noexcept {
  // A DIFOP without a usable angle table says nothing about the angles (it is counted as rejected).
  return motor_rpm != in_use.motor_rpm || return_mode != in_use.return_mode ||
         (has_angles && (!in_use.has_angles || angles.vertical_deg != in_use.angles.vertical_deg ||
                         angles.horizontal_deg != in_use.angles.horizontal_deg));
}

RsHeliosDecoder::Calibration RsHeliosDecoder::calibration_of(const HeliosDifop& difop) const noexcept {
  Calibration c;
  c.motor_rpm = difop.motor_rpm;
  c.return_mode = difop.return_mode;
  c.has_angles = difop.angles_valid && options_.use_difop_angles;
  if (c.has_angles) c.angles = difop.angles;
  return c;
}

void RsHeliosDecoder::apply(const Calibration& c) {
  msop_.set_rotation_hz(c.motor_rpm == 0 ? helios::kDefaultRotationHz : c.motor_rpm / 60.0);
  // The 16P's DIFOP carries 32 rows; its lasers are the first 16 (slot % 16, §8).
  if (c.has_angles)
    msop_.set_angles(std::span<const double>(c.angles.vertical_deg), std::span<const double>(c.angles.horizontal_deg));
  applied_ = c;
}

void RsHeliosDecoder::take(const Calibration& c, bool flag) {
  Calibration next = c;
  if (!next.has_angles && applied_) {  // the angles in use stay when the DIFOP has none
    next.has_angles = committed().has_angles;
    next.angles = committed().angles;
  }
  pending_ = next;
  pending_flags_ = flag;
  if (!sweeps_.sweep_open()) apply_pending(false);
}

void RsHeliosDecoder::apply_pending(bool sweep_open) {
  apply(*pending_);
  pending_.reset();
  // With a sweep open, the boundary ends it (its callback comes next); else the next sweep begins.
  if (pending_flags_) (sweep_open ? changed_at_next_start_ : flag_open_sweep_) = true;
  pending_flags_ = false;
}

void RsHeliosDecoder::on_difop(const HeliosDifop& difop) {
  ++stats_.difop;
  difop_ = difop;
  if (!difop.angles_valid) ++stats_.difop_angles_rejected;
  const Calibration c = calibration_of(difop);
  // The angles are pinned by the first DIFOP that has a usable table (until then the CSV's, a
  // fallback, are in use), the rest by the first DIFOP.
  Calibration known = applied_ ? committed() : c;
  const bool first_table = c.has_angles && !known.has_angles;
  if (first_table) {
    known.has_angles = true;
    known.angles = c.angles;
  }
  if (!applied_ || !msop_.has_angles() || (first_table && !c.differs_from(known))) {
    // The first calibration: taken, at the next sweep boundary if packets decoded with the CSV's
    // table are in a sweep (with no table at all none can be).
    take(c, false);
    disagrees_ = false;
  } else if (c.differs_from(known)) {
    ++stats_.calibration_changes;
    if (options_.calibration_updates == CalibrationUpdates::Follow) {
      take(c, true);
    } else {
      disagrees_ = true;
      flag_open_sweep_ = true;
    }
  } else {
    disagrees_ = false;
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
