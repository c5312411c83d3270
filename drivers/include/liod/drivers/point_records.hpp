#pragma once
// Binary point files of fixed-size little-endian float32 records, as datasets store their clouds:
// KITTI's velodyne .bin (x, y, z, reflectance) and the decoded Ouster sample's frames (x, y, z,
// reflectivity, seconds since the frame's first column). Parsed byte by byte (byte_order.hpp),
// whatever the host's byte order.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "liod/types.hpp"

namespace liod::drivers {

struct PointRecordLayout {
  /// float32 fields per record: x, y, z, intensity, then (with per-point time) the time.
  std::size_t fields = 4;
  bool has_time = false;  ///< the fifth field is the point's time, seconds after the sweep's start
};

inline constexpr PointRecordLayout kKittiVelodyneLayout{4, false};
inline constexpr PointRecordLayout kXyziTimeLayout{5, true};

/// The records of `bytes` as points (ring 0; time 0 without a time field). Throws InputError
/// naming `name` and the byte offset: a truncated last record, a time that is not finite or
/// negative. Non-finite coordinates are passed on (the front end drops them by range).
std::vector<LidarPoint> parse_point_records(std::span<const std::uint8_t> bytes, const PointRecordLayout& layout,
                                            const std::string& name);
/// The same, from a file (InputError naming it when it cannot be read).
std::vector<LidarPoint> read_point_records(const std::filesystem::path& path, const PointRecordLayout& layout);

}  // namespace liod::drivers
