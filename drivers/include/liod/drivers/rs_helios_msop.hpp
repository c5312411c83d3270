#pragma once
// RS-Helios MSOP (point data) packet decoding: one 1248-byte packet -> PacketPoints (spec §2-§4, §7,
// §8). Stateless per packet apart from the configuration (calibration, rotation rate); the sweep
// logic lives in SweepAssembler and the DIFOP/return-mode bookkeeping in RsHeliosDecoder.

#include <array>
#include <cstdint>
#include <span>

#include "liod/drivers/packet_points.hpp"
#include "liod/drivers/rs_helios_model.hpp"

namespace liod::drivers {

struct MsopHeader {
  std::uint16_t protocol_version = 0;
  std::uint32_t top_counter = 0;     ///< top-board packet counter (nebula)
  std::uint32_t bottom_counter = 0;  ///< bottom-board packet counter, +1 per packet
  std::uint8_t range_resolution_flag = 0;
  std::int64_t time_ns = 0;          ///< header UTC time: first firing of block 0 (§3)
  std::uint8_t lidar_type = 0;
  float temperature_c = 0.0F;
};

enum class MsopStatus : std::uint8_t {
  Ok,
  Partial,          ///< a broken block flag cut the packet; the blocks before it were decoded
  WrongSize,        ///< payload is not 1248 bytes
  BadMagic,         ///< not 55 AA 05 5A
  BadTimestamp,     ///< microseconds field >= 1e6, or seconds beyond helios::kMaxTimestampSeconds;
                    ///< with TimeSource::ArrivalTime also an arrival time outside 0 .. that bound
  BadAzimuth,       ///< a block azimuth >= 36000
  BrokenFirstBlock, ///< block 0 has no FF EE flag: nothing to decode
  NoCalibration,    ///< no angle table yet (rs_driver's wait_for_difop)
};

enum class RangeResolution : std::uint8_t {
  FromHeader,  ///< byte 17: 1 -> 2.5 mm, 0 -> 5 mm (nebula); other values -> 2.5 mm (rs_driver)
  Fixed2_5mm,  ///< rs_driver's hard-coded Helios value
  Fixed5mm,
};

enum class TimeSource : std::uint8_t {
  SensorClock,  ///< the MSOP header timestamp (PTP/GPS-synced sensors)
  ArrivalTime,  ///< arrival / capture time minus one packet duration (§3, rs_driver's fallback)
};

struct MsopDecoderOptions {
  float min_range_m = 0.1F;  ///< rs_driver's Helios limits (§2.2); nebula uses 0.2 .. 150 m
  float max_range_m = 180.0F;
  /// Lens-centre offset RX of §4; 0 reproduces decoders that leave it out.
  float lens_offset_m = static_cast<float>(helios::kLensOffsetRxM);
  RangeResolution range_resolution = RangeResolution::FromHeader;
  TimeSource time_source = TimeSource::SensorClock;
};

class MsopDecoder {
 public:
  MsopDecoder(HeliosModel model, MsopDecoderOptions options);

  /// Per-laser angles in packet order; the first beam_count(model) rows are used. Throws
  /// InputError when there are fewer rows than lasers.
  void set_angles(std::span<const double> vertical_deg, std::span<const double> horizontal_deg);
  [[nodiscard]] bool has_angles() const noexcept { return has_angles_; }
  /// Used for the nominal per-block azimuth step and the blind-zone time step (§3.2).
  void set_rotation_hz(double hz) noexcept;

  /// Decodes `payload`. `dual` selects the dual-return layout (§7, §8). `arrival_ns` is used only
  /// with TimeSource::ArrivalTime. On Ok/Partial, `out` holds the packet's points; `header` is
  /// filled whenever size and magic are right.
  MsopStatus decode(std::span<const std::uint8_t> payload, bool dual, std::int64_t arrival_ns,
                    PacketPoints& out, MsopHeader& header) const noexcept;

  /// Whether a 5515 packet has the dual-return block pattern: blocks 2k and 2k+1 share their
  /// azimuth (§7). Meaningless for the 16P, whose returns share a block.
  [[nodiscard]] static bool looks_dual_return(std::span<const std::uint8_t> payload) noexcept;

  [[nodiscard]] HeliosModel model() const noexcept { return model_; }
  /// Ring of each laser (rank by elevation), valid once angles are set.
  [[nodiscard]] std::span<const std::uint16_t> rings() const noexcept;

 private:
  struct SlotEntry {
    std::uint8_t laser = 0;
    std::uint8_t return_index = 0;
    float time_s = 0.0F;       // firing offset after the block time
    float az_fraction = 0.0F;  // fraction of the block azimuth step covered at firing
  };
  struct LaserEntry {
    float cos_el = 1.0F;
    float sin_el = 0.0F;
    float horizontal_units = 0.0F;  // 0.01°
  };

  void build_slot_tables() noexcept;

  HeliosModel model_;
  MsopDecoderOptions options_;
  bool has_angles_ = false;
  double rotation_hz_ = helios::kDefaultRotationHz;
  std::int32_t nominal_step_ = 20;
  std::array<SlotEntry, 32> single_slots_{};
  std::array<SlotEntry, 32> dual_slots_{};
  std::array<LaserEntry, 32> lasers_{};
  std::array<std::uint16_t, 32> rings_{};
  /// cos/sin of every azimuth in 0.01° steps (one more at 360° for the interpolation), built once
  /// and shared by every decoder: it keeps trigonometry out of the per-point loop.
  std::span<const std::array<float, 2>> trig_;
};

}  // namespace liod::drivers
