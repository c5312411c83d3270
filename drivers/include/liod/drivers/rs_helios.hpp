#pragma once
// RS-Helios stream decoder: feed it every UDP payload from the sensor (MSOP and DIFOP, told apart
// by magic, spec §1) and it calls back with each finished sweep. Owns the stream state rs_driver
// keeps: calibration (DIFOP, else the angle CSV), return mode (DIFOP, else detected), rotation
// rate, packet-loss accounting, and the sweep split.
//
//   RsHeliosDecoder dec(options, [&](liod::Scan& scan, const SweepInfo& info) {
//     std::swap(scan, my_recycled_scan);  // allocation-free hand-off
//     ...
//   });
//   while (reader.next(d)) dec.feed(d.payload, d.capture_time_ns);
//   dec.flush();

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "liod/drivers/packet_points.hpp"
#include "liod/drivers/rs_helios_calibration.hpp"
#include "liod/drivers/rs_helios_difop.hpp"
#include "liod/drivers/rs_helios_model.hpp"
#include "liod/drivers/rs_helios_msop.hpp"
#include "liod/drivers/sweep_assembler.hpp"

namespace liod::drivers {

enum class ReturnModePolicy : std::uint8_t {
  Auto,        ///< DIFOP's return-mode byte; before any DIFOP, single unless a 5515 packet has the
               ///< duplicated-azimuth dual pattern (§7). (The 16P's dual layout cannot be detected.)
  ForceSingle,
  ForceDual,
};

/// What a DIFOP after the first does to the calibration in use (its angle table, rotation rate
/// and return mode). Either way a DIFOP that differs is counted (HeliosStats::calibration_changes)
/// and flagged (SweepInfo::calibration_changed), and no sweep is decoded with two calibrations.
enum class CalibrationUpdates : std::uint8_t {
  Pin,     ///< the first DIFOP's calibration stays until restart; sweeps are flagged while the
           ///< sensor's latest DIFOP disagrees with it
  Follow,  ///< the latest calibration is taken at the next sweep boundary; the first sweep decoded
           ///< with it is flagged
};

struct HeliosOptions {
  HeliosModel model = HeliosModel::Helios5515;
  /// Angle table from load_angles_csv (rows == lasers). A valid DIFOP table replaces it when
  /// use_difop_angles is set (spec §5). Without either, MSOP packets are counted and dropped.
  std::optional<AngleTable> angles;
  bool use_difop_angles = true;
  MsopDecoderOptions msop;
  ReturnModePolicy return_mode = ReturnModePolicy::Auto;
  CalibrationUpdates calibration_updates = CalibrationUpdates::Pin;
  double split_azimuth_deg = 0.0;
  double max_block_gap_s = 0.05;
  bool emit_partial_sweep_on_flush = false;
  /// Without an angle table, MSOP packets that arrive before the first DIFOP are held (up to
  /// this many, the rest refused as no_calibration) and decoded, in order, once it arrives:
  /// live, MSOP and DIFOP come on two sockets, and the first sweep would otherwise lose the
  /// packets that raced ahead of the calibration. 0 = refuse them at once (rs_driver's
  /// wait_for_difop).
  std::size_t max_held_packets = 0;
};

struct HeliosStats {
  std::uint64_t msop = 0;   ///< MSOP packets decoded (fully or up to a broken block flag)
  std::uint64_t difop = 0;  ///< DIFOP packets parsed
  std::uint64_t points = 0;
  // Packets refused, by reason.
  std::uint64_t wrong_size = 0;
  std::uint64_t bad_magic = 0;  ///< neither MSOP nor DIFOP magic
  std::uint64_t bad_timestamp = 0;
  std::uint64_t bad_azimuth = 0;
  std::uint64_t broken_first_block = 0;
  std::uint64_t no_calibration = 0;
  std::uint64_t held_for_calibration = 0;  ///< MSOP held until the first DIFOP, then decoded
  // Accepted with a defect.
  std::uint64_t broken_block_flag = 0;      ///< decoded only up to a broken block flag
  std::uint64_t difop_angles_rejected = 0;  ///< DIFOPs whose angle table failed §6's checks
  std::uint64_t unknown_range_flag = 0;     ///< header byte 17 neither 0 nor 1 (2.5 mm assumed)
  std::uint64_t calibration_changes = 0;    ///< DIFOPs whose calibration differs from the one in use
  // Stream continuity.
  std::uint64_t lost_packets = 0;     ///< gaps in the bottom-board packet counter
  std::uint64_t counter_resets = 0;   ///< counter went backwards or jumped implausibly far
  std::uint64_t azimuth_jumps = 0;    ///< packet-to-packet azimuth step > 1° (loss or blind zone)
  std::uint64_t time_gaps = 0;        ///< sweeps cut short by a time gap or a clock step
  std::uint64_t truncated_sweeps = 0; ///< sweeps cut at the block cap: the azimuth never crossed the split
  std::uint64_t largest_sweep_points = 0;  ///< the most points one sweep handed out held
  std::uint64_t duplicate_packets = 0;  ///< repeats of a recent packet (same header time), ignored
  std::uint64_t late_packets = 0;       ///< arrived after later ones: added to their sweep in time order
  std::uint64_t late_packets_dropped = 0;  ///< arrived after their sweep was out
  std::uint64_t sweeps = 0;
  std::uint64_t partial_sweeps_dropped = 0;

  [[nodiscard]] std::uint64_t rejected() const noexcept {
    return wrong_size + bad_magic + bad_timestamp + bad_azimuth + broken_first_block + no_calibration;
  }
};

enum class PacketKind : std::uint8_t { Msop, Difop, Rejected };

/// A 1248-byte payload with the MSOP or the DIFOP magic (spec §1): what an RS-Helios sends.
[[nodiscard]] bool is_helios_packet(std::span<const std::uint8_t> payload) noexcept;

class RsHeliosDecoder {
 public:
  using SweepCallback = SweepAssembler::Callback;

  /// Throws InputError when options.angles does not have one row per laser.
  RsHeliosDecoder(HeliosOptions options, SweepCallback on_sweep);

  /// One UDP payload; `arrival_ns` is the capture/arrival time (used for TimeSource::ArrivalTime).
  /// May call the sweep callback. Never throws on bad packets: they are counted in stats().
  PacketKind feed(std::span<const std::uint8_t> payload, std::int64_t arrival_ns = 0);
  /// End of stream; see SweepOptions::emit_partial_on_flush.
  void flush();

  [[nodiscard]] HeliosStats stats() const noexcept;
  [[nodiscard]] const std::optional<HeliosDifop>& last_difop() const noexcept { return difop_; }
  /// True when the last decoded MSOP packet was decoded with the dual-return layout.
  [[nodiscard]] bool dual_return() const noexcept { return last_dual_; }
  [[nodiscard]] HeliosModel model() const noexcept { return options_.model; }

 private:
  /// A DIFOP's calibration: what the decoding depends on.
  struct Calibration {
    std::uint16_t motor_rpm = 0;
    std::uint8_t return_mode = 0;
    bool has_angles = false;  ///< a valid DIFOP table taken (use_difop_angles)
    DifopAngles angles;
    [[nodiscard]] bool differs_from(const Calibration& in_use) const noexcept;
  };
  [[nodiscard]] Calibration calibration_of(const HeliosDifop& difop) const noexcept;
  /// What new DIFOPs are compared with: the calibration decoded with, or the one waiting for the
  /// next sweep boundary.
  [[nodiscard]] const Calibration& committed() const noexcept { return pending_ ? *pending_ : *applied_; }
  /// Commits to `c`: now when no sweep is open, else at the next sweep boundary.
  void take(const Calibration& c, bool flag);
  void apply(const Calibration& c);
  void apply_pending(bool sweep_open);
  void on_difop(const HeliosDifop& difop);
  /// Hands the decoded packet to the sweeps; a change waiting for a sweep boundary (follow) is
  /// applied there, and the packet's blocks from the boundary on decoded again with it.
  void add_to_sweeps(std::span<const std::uint8_t> payload, std::int64_t arrival_ns);
  void on_assembled(Scan& scan, const SweepInfo& info);
  /// Keeps an MSOP packet that came before any calibration; false when it cannot be kept.
  bool hold(std::span<const std::uint8_t> payload, std::int64_t arrival_ns);
  void decode_held();
  void on_msop_header(const MsopHeader& header);
  [[nodiscard]] bool packet_is_dual(std::span<const std::uint8_t> payload) const noexcept;

  HeliosOptions options_;
  SweepCallback on_sweep_;
  MsopDecoder msop_;
  SweepAssembler sweeps_;
  std::optional<Calibration> applied_;  // decoded with, since the first DIFOP
  std::optional<Calibration> pending_;  // taken at the next sweep boundary
  bool pending_flags_ = false;          // the first sweep decoded with pending_ is flagged
  bool disagrees_ = false;              // pin: the latest DIFOP differs from committed()
  bool flag_open_sweep_ = false;        // the sweep being assembled is flagged calibration_changed
  bool changed_at_next_start_ = false;  // the next sweep is the first with a new calibration
  PacketPoints packet_;
  MsopHeader header_;
  HeliosDifop scratch_difop_;
  std::optional<HeliosDifop> difop_;
  HeliosStats stats_;
  bool have_counter_ = false;
  std::uint32_t last_counter_ = 0;
  bool have_azimuth_ = false;
  std::uint16_t last_azimuth_ = 0;
  bool last_dual_ = false;
  struct HeldPacket {
    std::vector<std::uint8_t> payload;
    std::int64_t arrival_ns = 0;
  };
  std::vector<HeldPacket> held_;
};

}  // namespace liod::drivers
