#pragma once
// Per-laser angle calibration of an RS-Helios: vertical (elevation) angle and horizontal azimuth
// offset, in packet channel order (spec §5). Comes from DIFOP (rs_helios_difop.hpp) or from an
// angle CSV file (`vertical_deg,horizontal_deg`, one line per channel).

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace liod::drivers {

struct AngleTable {
  std::vector<double> vertical_deg;    ///< elevation, + up
  std::vector<double> horizontal_deg;  ///< added to the channel azimuth (packet azimuth convention)

  [[nodiscard]] std::size_t size() const noexcept { return vertical_deg.size(); }
};

/// Reads an angle CSV: one `vertical_deg,horizontal_deg` row per channel; surrounding whitespace
/// (incl. the tabs and CR of the files RoboSense/nebula ship), blank lines and `#` comments are
/// ignored. Throws InputError naming the file and line for a missing file, a bad number, a wrong
/// column count, a non-finite or out-of-range angle, or an empty table.
[[nodiscard]] AngleTable load_angles_csv(const std::filesystem::path& path);
/// Same, from text already in memory; `name` is used in error messages.
[[nodiscard]] AngleTable parse_angles_csv(std::string_view text, const std::string& name);

/// Ring number of each channel: the rank of its elevation, 0 = lowest (spec §4, rs_driver's
/// "user channel"). Equal elevations are ranked by channel index so rings stay unique.
[[nodiscard]] std::vector<std::uint16_t> rings_by_elevation(std::span<const double> vertical_deg);
/// Same, into `rings` (size >= vertical_deg.size()) without allocating.
void rings_by_elevation(std::span<const double> vertical_deg, std::span<std::uint16_t> rings) noexcept;

}  // namespace liod::drivers
