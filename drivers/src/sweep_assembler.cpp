#include "liod/drivers/sweep_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "liod/drivers/rs_helios_model.hpp"

namespace liod::drivers {
namespace {
using helios::kFullCircle;
// Consecutive blocks further apart than 1° straddle the blind zone or a loss (§3).
using helios::kBlindZoneJump;
}  // namespace

SweepAssembler::SweepAssembler(SweepOptions options, Callback on_sweep)
    : options_(options), on_sweep_(std::move(on_sweep)) {
  double split = std::fmod(options_.split_azimuth_deg, 360.0);
  if (split < 0) split += 360.0;
  split_units_ = static_cast<std::int32_t>(std::lround(split * 100.0)) % kFullCircle;
  current_.beam_count = options_.beam_count;
  current_.points.reserve(options_.reserve_points);
}

bool SweepAssembler::crosses_split(std::uint16_t prev, std::uint16_t az) const noexcept {
  // Unwrap prev below az when the azimuth wrapped, then ask whether split lies in (prev, az].
  // A step back by less than half a turn is a late or repeated packet, not a wrap.
  std::int32_t p = prev;
  if (az < prev) {
    if (prev - az < kFullCircle / 2) return false;
    p -= kFullCircle;
  }
  const std::int32_t a = az;
  return (p < split_units_ && split_units_ <= a) ||
         (p < split_units_ - kFullCircle && split_units_ - kFullCircle <= a);
}

void SweepAssembler::start_sweep(std::int64_t block_time_ns, std::uint16_t azimuth) {
  open_ = true;
  reference_ns_ = block_time_ns;
  info_ = SweepInfo{};
  info_.first_azimuth = azimuth;
  current_.points.clear();
  current_.beam_count = options_.beam_count;
}

bool SweepAssembler::repeats_recent(const PacketPoints& packet) noexcept {
  const PacketKey key{packet.time_ns, packet.blocks[0].azimuth};
  if (std::find(recent_packets_.begin(), recent_packets_.end(), key) != recent_packets_.end()) return true;
  recent_packets_[recent_next_] = key;
  recent_next_ = (recent_next_ + 1) % recent_packets_.size();
  return false;
}

void SweepAssembler::add_late(const PacketPoints& packet) {
  if (packet.time_ns < reference_ns_ || info_.blocks + packet.block_count > options_.max_blocks) {
    ++late_dropped_;
    return;
  }
  ++late_;
  ++info_.packets;
  info_.blocks += static_cast<std::uint32_t>(packet.block_count);
  // Into the sweep where its time belongs: the feature extraction walks each ring in time order.
  const double packet_to_ref_s = static_cast<double>(packet.time_ns - reference_ns_) * 1e-9;
  std::array<LidarPoint, PacketPoints::kMaxPoints> rebased;
  for (std::size_t i = 0; i < packet.point_count; ++i) {
    rebased[i] = packet.points[i];
    rebased[i].time = static_cast<float>(packet_to_ref_s + static_cast<double>(packet.points[i].time));
  }
  auto& points = current_.points;
  const float first = packet.point_count > 0 ? rebased[0].time : 0.0F;
  const auto at = std::upper_bound(points.begin(), points.end(), first,
                                   [](float t, const LidarPoint& p) { return t < p.time; });
  points.insert(at, rebased.begin(), rebased.begin() + static_cast<std::ptrdiff_t>(packet.point_count));
}

std::int64_t SweepAssembler::block_time_ns(const PacketPoints& packet, std::size_t b) noexcept {
  return packet.time_ns + static_cast<std::int64_t>(std::llround(static_cast<double>(packet.blocks[b].time_offset_s) * 1e9));
}

SweepAssembler::Boundary SweepAssembler::boundary(std::int64_t last_ns, std::uint16_t last_az, std::uint32_t blocks,
                                                  std::int64_t block_ns, std::uint16_t az) const noexcept {
  const double gap_s = static_cast<double>(block_ns - last_ns) * 1e-9;
  if (gap_s < 0.0 || gap_s > options_.max_block_gap_s) return Boundary::Gap;
  if (crosses_split(last_az, az)) return Boundary::Split;
  if (blocks >= options_.max_blocks) return Boundary::Full;
  return Boundary::None;
}

bool SweepAssembler::is_late(const PacketPoints& packet) const noexcept {
  const double late_s = static_cast<double>(last_block_ns_ - block_time_ns(packet, 0)) * 1e-9;
  return open_ && late_s > 0.0 && late_s <= options_.max_block_gap_s;
}

std::size_t SweepAssembler::next_sweep_block(const PacketPoints& packet) const noexcept {
  if (!open_) return 0;
  const PacketKey key{packet.time_ns, packet.blocks[0].azimuth};
  if (packet.block_count == 0 || is_late(packet) ||
      std::find(recent_packets_.begin(), recent_packets_.end(), key) != recent_packets_.end())
    return packet.block_count;
  std::int64_t last_ns = last_block_ns_;
  std::uint16_t last_az = last_azimuth_;
  std::uint32_t blocks = info_.blocks;
  for (std::size_t b = 0; b < packet.block_count; ++b, ++blocks) {
    const std::int64_t block_ns = block_time_ns(packet, b);
    if (boundary(last_ns, last_az, blocks, block_ns, packet.blocks[b].azimuth) != Boundary::None) return b;
    last_ns = block_ns;
    last_az = packet.blocks[b].azimuth;
  }
  return packet.block_count;
}

void SweepAssembler::add(const PacketPoints& packet) { add_blocks(packet, 0, packet.block_count); }

void SweepAssembler::add_blocks(const PacketPoints& packet, std::size_t first, std::size_t end) {
  end = std::min(end, packet.block_count);
  if (first >= end) return;
  if (first == 0) {
    if (repeats_recent(packet)) {
      ++duplicates_;
      return;
    }
    if (is_late(packet)) {
      add_late(packet);
      return;
    }
  }
  bool counted_packet = false;
  for (std::size_t b = first; b < end; ++b) {
    const FiringBlock& block = packet.blocks[b];
    const std::int64_t block_ns = block_time_ns(packet, b);
    if (!open_) {
      start_sweep(block_ns, block.azimuth);
    } else {
      const Boundary ends = boundary(last_block_ns_, last_azimuth_, info_.blocks, block_ns, block.azimuth);
      const std::int32_t step = (block.azimuth - last_azimuth_ + kFullCircle) % kFullCircle;
      if (ends != Boundary::Gap && step <= kBlindZoneJump) info_.azimuth_coverage_deg += step * 0.01;
      if (ends != Boundary::None) {
        info_.ended_by_gap = ends == Boundary::Gap;
        // A sweep that began at a cut holds what was left of the run that never crossed the split.
        const bool began_at_cut = info_.truncated;
        info_.truncated = began_at_cut || ends == Boundary::Full;
        if (ends == Boundary::Gap) ++time_gaps_;
        if (info_.truncated) ++truncated_;
        finish_sweep();
        start_sweep(block_ns, block.azimuth);
        info_.truncated = ends == Boundary::Full;
        counted_packet = false;
      }
    }
    if (!counted_packet) {
      ++info_.packets;
      counted_packet = true;
    }
    ++info_.blocks;
    info_.last_azimuth = block.azimuth;
    last_azimuth_ = block.azimuth;
    last_block_ns_ = block_ns;

    // Rebase the block's points from packet time onto the sweep's reference time.
    const double packet_to_ref_s = static_cast<double>(packet.time_ns - reference_ns_) * 1e-9;
    const std::size_t end_point = std::size_t{block.first_point} + block.point_count;
    for (std::size_t i = block.first_point; i < end_point; ++i) {
      LidarPoint p = packet.points[i];
      p.time = static_cast<float>(packet_to_ref_s + static_cast<double>(p.time));
      current_.points.push_back(p);
    }
  }
}

void SweepAssembler::finish_sweep() {
  // start_time is the earliest point, not the first block: the first block's first slots may have
  // had no return, and firing order is not monotonic in slot order (§3.1).
  float t_min = 0.0F;
  float t_max = 0.0F;
  if (!current_.points.empty()) {
    t_min = std::numeric_limits<float>::max();
    t_max = std::numeric_limits<float>::lowest();
    for (const LidarPoint& p : current_.points) {
      t_min = std::min(t_min, p.time);
      t_max = std::max(t_max, p.time);
    }
    for (LidarPoint& p : current_.points) p.time -= t_min;
  }
  const double reference_s = static_cast<double>(reference_ns_) * 1e-9;
  current_.start_time = reference_s + static_cast<double>(t_min);
  current_.end_time = reference_s + static_cast<double>(t_max);
  current_.sequence = next_sequence_++;
  largest_points_ = std::max(largest_points_, current_.points.size());
  current_.beam_count = options_.beam_count;
  on_sweep_(current_, info_);
  current_.points.clear();
  open_ = false;
}

void SweepAssembler::flush() {
  if (!open_) return;
  if (options_.emit_partial_on_flush && info_.blocks > 0) {
    info_.flushed = true;
    if (info_.truncated) ++truncated_;
    finish_sweep();
  } else {
    ++partial_dropped_;
    current_.points.clear();
    open_ = false;
  }
}

}  // namespace liod::drivers
