#pragma once
// Cuts the stream of decoded packets into sweeps (liod::Scan), splitting at a configurable block
// azimuth like rs_driver's split-by-angle (spec §9), and rebasing point times onto the sweep.
//
// Allocation: the working Scan keeps its capacity from sweep to sweep. The callback receives the
// finished Scan by reference; to stay allocation-free it should std::swap it with a Scan it
// recycles (whatever is left in the reference is cleared and becomes the next working buffer).
// Moving out of it also works but costs one allocation per sweep.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>

#include "liod/drivers/packet_points.hpp"
#include "liod/drivers/rs_helios_model.hpp"
#include "liod/types.hpp"

namespace liod::drivers {

struct SweepOptions {
  /// A sweep starts at the first block whose azimuth crosses this angle (the 359.99° → 0° wrap
  /// counts as crossing 0°).
  double split_azimuth_deg = 0.0;
  /// A jump in block time larger than this (or backwards) ends the sweep early: lost packets or
  /// a clock step make the azimuth test unreliable across the gap.
  double max_block_gap_s = 0.05;
  /// flush() emits a last, incomplete sweep only when this is set; by default an end of stream
  /// drops it (a SLAM front end would otherwise see a fragment). The first sweep of a stream is
  /// always emitted even though it usually starts mid-revolution: SweepInfo::azimuth_coverage_deg
  /// tells consumers how complete it is (rs_driver and nebula emit it too).
  bool emit_partial_on_flush = false;
  std::uint16_t beam_count = 32;
  /// A sweep that reaches this many blocks without crossing the split is cut there (counted,
  /// SweepInfo::truncated, as is the sweep that follows the cut): the memory a sweep holds stays
  /// bounded whatever the azimuths say.
  std::uint32_t max_blocks = helios::kMaxSweepBlocks;
  /// Capacity reserved up front for the working sweep (points).
  std::size_t reserve_points = 0;
};

/// What the assembler knows about a sweep beyond the Scan itself.
struct SweepInfo {
  std::uint16_t first_azimuth = 0;  ///< 0.01°
  std::uint16_t last_azimuth = 0;   ///< 0.01°
  std::uint32_t blocks = 0;         ///< firing blocks (a dual-return pair counts twice)
  std::uint32_t packets = 0;        ///< packets with at least one block in this sweep
  /// Sum of the azimuth steps between consecutive firings, ignoring jumps > 1° (blind zone, loss).
  double azimuth_coverage_deg = 0.0;
  bool ended_by_gap = false;  ///< cut by a time gap rather than by the split azimuth
  /// Cut at SweepOptions::max_blocks at its end or its start: the azimuth had not crossed the
  /// split for that many blocks (begun at such a cut, it holds the rest of that run).
  bool truncated = false;
  /// Set by RsHeliosDecoder: the sensor's DIFOP disagreed with the calibration this sweep was
  /// decoded with (CalibrationUpdates::Pin), or this is the first sweep of a new one (Follow).
  bool calibration_changed = false;
  bool flushed = false;       ///< emitted by flush() (incomplete)
};

class SweepAssembler {
 public:
  using Callback = std::function<void(Scan& scan, const SweepInfo& info)>;

  SweepAssembler(SweepOptions options, Callback on_sweep);

  /// A packet with the header time and first azimuth of one of the last few is a repeat and
  /// adds nothing. One
  /// that arrives after later ones (reordered on the way; older than the newest block by up to
  /// max_block_gap_s) joins the open sweep in time order without moving the split, or is
  /// dropped when it is older than the open sweep (its sweep is already out) or would take the
  /// sweep past max_blocks.
  void add(const PacketPoints& packet);
  /// Blocks [first, end) of `packet` only, for a packet fed in two parts at a sweep boundary (see
  /// next_sweep_block): its head with first = 0 goes through add()'s checks; a tail (first > 0)
  /// is taken as the rest of a packet already checked, and may be a new decoding of it.
  void add_blocks(const PacketPoints& packet, std::size_t first, std::size_t end);
  /// The block of `packet` with which add() would begin a new sweep (the split crossed, a time
  /// gap, max_blocks reached; 0 when no sweep is open), or packet.block_count when all of it would
  /// join the open sweep (or be ignored as a repeat, or merged as late).
  [[nodiscard]] std::size_t next_sweep_block(const PacketPoints& packet) const noexcept;
  [[nodiscard]] bool sweep_open() const noexcept { return open_; }
  /// End of stream: emits the open sweep if it has blocks and options.emit_partial_on_flush is
  /// set, otherwise drops it (counted). Then starts afresh.
  void flush();

  [[nodiscard]] std::uint64_t sweeps_emitted() const noexcept { return next_sequence_; }
  [[nodiscard]] std::uint64_t partial_sweeps_dropped() const noexcept { return partial_dropped_; }
  [[nodiscard]] std::uint64_t time_gaps() const noexcept { return time_gaps_; }
  [[nodiscard]] std::uint64_t duplicate_packets() const noexcept { return duplicates_; }
  [[nodiscard]] std::uint64_t late_packets() const noexcept { return late_; }
  [[nodiscard]] std::uint64_t late_packets_dropped() const noexcept { return late_dropped_; }
  [[nodiscard]] std::uint64_t truncated_sweeps() const noexcept { return truncated_; }
  [[nodiscard]] std::size_t largest_sweep_points() const noexcept { return largest_points_; }

 private:
  enum class Boundary : std::uint8_t { None, Gap, Split, Full };
  [[nodiscard]] static std::int64_t block_time_ns(const PacketPoints& packet, std::size_t b) noexcept;
  /// Whether a block at `block_ns`, `az` ends a sweep of `blocks` blocks whose last one was at
  /// `last_ns`, `last_az`, and why.
  [[nodiscard]] Boundary boundary(std::int64_t last_ns, std::uint16_t last_az, std::uint32_t blocks,
                                  std::int64_t block_ns, std::uint16_t az) const noexcept;
  [[nodiscard]] bool is_late(const PacketPoints& packet) const noexcept;
  [[nodiscard]] bool repeats_recent(const PacketPoints& packet) noexcept;
  void add_late(const PacketPoints& packet);
  void start_sweep(std::int64_t block_time_ns, std::uint16_t azimuth);
  void finish_sweep();
  [[nodiscard]] bool crosses_split(std::uint16_t prev, std::uint16_t az) const noexcept;

  SweepOptions options_;
  Callback on_sweep_;
  std::int32_t split_units_ = 0;
  Scan current_;
  SweepInfo info_;
  bool open_ = false;
  std::int64_t reference_ns_ = 0;    // time base of current_'s point times until finish
  std::int64_t last_block_ns_ = 0;
  std::uint16_t last_azimuth_ = 0;
  std::uint64_t next_sequence_ = 0;
  std::uint64_t partial_dropped_ = 0;
  std::uint64_t time_gaps_ = 0;
  struct PacketKey {
    std::int64_t time_ns = std::numeric_limits<std::int64_t>::min();
    std::uint16_t azimuth = 0;
    bool operator==(const PacketKey&) const = default;
  };
  std::array<PacketKey, 16> recent_packets_{};  // the last packets, to recognise repeats
  std::size_t recent_next_ = 0;
  std::uint64_t duplicates_ = 0;
  std::uint64_t late_ = 0;
  std::uint64_t late_dropped_ = 0;
  std::uint64_t truncated_ = 0;
  std::size_t largest_points_ = 0;
};

}  // namespace liod::drivers
