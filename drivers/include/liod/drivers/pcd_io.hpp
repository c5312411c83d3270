#pragma once
// PCD files: writing a liod::Scan as binary PCD (fields x y z intensity time ring, as PCL reads
// them), and a reader for ASCII and binary (uncompressed) PCD good enough for the reference clouds
// in shared/data/robosense/*_decoded/ (x y z intensity return_type channel azimuth elevation
// distance time_stamp). Hand-written: the format is a dozen header lines and packed records, and
// keeping PCL's heavy headers and link dependencies out of liod_drivers matters more than reuse.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "liod/types.hpp"

namespace liod::drivers {

/// Writes `scan` as binary PCD: x y z intensity time (F4, time = s after scan.start_time) and
/// ring (U2). A `# liod ...` comment line carries sequence, start/end time and beam count (PCL
/// skips comment lines). Throws InputError on I/O failure.
void write_pcd_binary(const std::filesystem::path& path, const Scan& scan);

/// A PCD file's fields and values (all converted to double), row-major.
struct PcdCloud {
  std::vector<std::string> fields;  ///< fields with COUNT > 1 appear as name, name_1, name_2, ...
  std::size_t width = 0;
  std::size_t height = 0;
  std::vector<double> values;       ///< points() * fields.size()

  [[nodiscard]] std::size_t points() const noexcept { return fields.empty() ? 0 : values.size() / fields.size(); }
  /// Column of `name`, or -1.
  [[nodiscard]] int field_index(std::string_view name) const noexcept;
  [[nodiscard]] double value(std::size_t point, std::size_t field) const noexcept {
    return values[point * fields.size() + field];
  }
};

/// Reads DATA ascii or binary PCD (binary_compressed throws). Throws InputError naming the file
/// (and the line, for ASCII) on a malformed header or a short/garbled body.
[[nodiscard]] PcdCloud read_pcd(const std::filesystem::path& path);

/// The fields the tests and odometry need from a decoded LiDAR cloud.
struct PcdPoint {
  float x = 0.0F;
  float y = 0.0F;
  float z = 0.0F;
  float intensity = 0.0F;
  std::uint16_t channel = 0;  ///< `channel` or `ring` field (ring order), 0 if absent
  double time_stamp = 0.0;    ///< `time_stamp`, `timestamp` or `time` field, 0 if absent
};

/// read_pcd + pick x y z (required) and intensity, channel/ring, time_stamp/time (optional).
[[nodiscard]] std::vector<PcdPoint> read_pcd_points(const std::filesystem::path& path);

}  // namespace liod::drivers
