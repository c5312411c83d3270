#pragma once
// sensor_msgs/PointCloud2 and sensor_msgs/Imu from their serialized bytes, ROS 1's serialization
// (little-endian, packed, a seq before the stamp) or ROS 2's CDR (a 4-byte encapsulation header,
// then either byte order with each primitive aligned to its size), into the point-cloud path's
// sweep (cloud_sweep.hpp) and liod's IMU sample. Every length is checked against the bytes there.
//
// PointCloud2's fields, by name (the drivers' conventions):
//   x, y, z          float32 or float64, metres, the cloud's frame (required)
//   intensity        any numeric type (Ouster and Velodyne float32, Hesai uint8, Livox float32)
//   per-point time   the first of: t (Ouster, uint32 ns after the stamp), time (Velodyne, float32 s
//                    after the stamp), offset_time (Livox, uint32 ns after the stamp), timestamp
//                    (Hesai and RoboSense float64 s since the epoch; above 1e14 it is read as ns,
//                    as livox_ros_driver2 writes it)
//   ring or line     the point's beam (uint16 or uint8; Livox's "line"); required
// point_step, row_step, height (organized clouds), is_bigendian and the header's stamp are honoured.
// A cloud with per-point time begins at its earliest point; without, at its stamp (the head's
// sweep start, times then taken from azimuth by make_scan).

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "liod/drivers/bag_reader.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/types.hpp"

namespace liod::drivers {

/// A message header's stamp (ROS 1: u32 seconds; ROS 2: i32 seconds; both with u32 nanoseconds).
struct RosStamp {
  std::int64_t sec = 0;
  std::uint32_t nsec = 0;
  [[nodiscard]] double seconds() const { return static_cast<double>(sec) + static_cast<double>(nsec) * 1e-9; }
};

/// PointField's datatype constants (sensor_msgs/PointField).
enum class PointDatatype : std::uint8_t { Int8 = 1, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

struct PointField {
  std::string name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 1;
};

struct PointCloud2 {
  RosStamp stamp;
  std::string frame_id;
  std::uint32_t height = 0, width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0, row_step = 0;
  std::span<const std::uint8_t> data;  ///< into the message's bytes
  bool is_dense = false;
};

/// InputError naming `name` when the bytes are not a whole message of this type in `encoding`.
PointCloud2 decode_point_cloud2(std::span<const std::uint8_t> bytes, MessageEncoding encoding, const std::string& name);
/// angular_velocity and linear_acceleration (specific force, REP 145) at the header's stamp.
ImuSample decode_imu(std::span<const std::uint8_t> bytes, MessageEncoding encoding, const std::string& name);

struct CloudConversionStats {
  std::size_t not_finite = 0;  ///< points with a coordinate that is not finite (dropped)
};

/// The cloud as a sweep with per-point ring and (where a time field is there) time. InputError
/// naming `name`: no x, y, z or ring field, a field that does not fit point_step, data shorter
/// than height x row_step, a ring outside 0..1023, a finite point with a time that is not, or
/// per-point times spanning more than a second (wrong units).
CloudSweep cloud_sweep(const PointCloud2& cloud, const std::string& name, std::uint64_t sequence,
                       CloudConversionStats* stats = nullptr);

/// The ROS types the two decoders read, as a ROS 1 bag and a ROS 2 MCAP name them.
bool is_point_cloud2_type(const std::string& type);
bool is_imu_type(const std::string& type);

}  // namespace liod::drivers
