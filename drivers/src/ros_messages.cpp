#include "liod/drivers/ros_messages.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <optional>

#include "field_cursor.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

using detail::CursorStyle;
using detail::FieldCursor;

/// A cursor at the message's first field. CDR: after the encapsulation header (RTPS 10.5: 0x0000
/// plain CDR big-endian, 0x0001 little-endian; alignment counts from the byte after it).
FieldCursor message_cursor(std::span<const std::uint8_t> bytes, MessageEncoding encoding, const std::string& name) {
  if (encoding == MessageEncoding::Ros1) return FieldCursor(bytes, name);
  if (encoding != MessageEncoding::Cdr) throw InputError(name, 0, "messages in an encoding other than ros1 or cdr");
  if (bytes.size() < 4) throw InputError(name, 0, "CDR message shorter than its 4-byte encapsulation header");
  if (bytes[0] != 0 || bytes[1] > 1) {
    throw InputError(name, 0, "CDR encapsulation " + std::to_string(bytes[0] * 256 + bytes[1]) +
                                  ": only plain CDR (0 big-endian, 1 little-endian) is read");
  }
  CursorStyle style;
  style.big_endian = bytes[1] == 0;
  style.max_align = 8;
  style.nul_terminated_strings = true;
  return FieldCursor(bytes.subspan(4), name, 4, style);
}

/// std_msgs/Header: ROS 1 has a seq before the stamp, ROS 2 none.
RosStamp header(FieldCursor& c, MessageEncoding encoding, std::string* frame_id) {
  RosStamp s;
  if (encoding == MessageEncoding::Ros1) {
    c.skip(4, "header seq");
    s.sec = c.u32("header stamp seconds");
  } else {
    s.sec = c.i32("header stamp seconds");
  }
  s.nsec = c.u32("header stamp nanoseconds");
  if (s.nsec >= 1'000'000'000U) c.fail("header stamp nanoseconds " + std::to_string(s.nsec) + " not below 1e9");
  std::string frame = c.string("header frame_id");
  if (frame_id != nullptr) *frame_id = std::move(frame);
  return s;
}

/// The message must end here: ROS 1 exactly, CDR up to the 3 bytes that pad a payload to a
/// multiple of 4 (RTPS 10.5). Bytes beyond are a message of another type.
void expect_end(const FieldCursor& c, MessageEncoding encoding, const char* type) {
  if (c.remaining() > (encoding == MessageEncoding::Cdr ? 3U : 0U)) {
    c.fail(std::to_string(c.remaining()) + " bytes after the end of a " + type + ": a message of another type?");
  }
}

Eigen::Vector3d vector3(FieldCursor& c, const char* what) {
  const double x = c.f64(what), y = c.f64(what), z = c.f64(what);
  return {x, y, z};
}

std::size_t datatype_bytes(std::uint8_t datatype) {
  constexpr std::array<std::size_t, 9> kBytes{0, 1, 1, 2, 2, 4, 4, 4, 8};
  return datatype < kBytes.size() ? kBytes[datatype] : 0;
}

/// One field of a point, read as a double.
struct FieldReader {
  std::uint32_t offset = 0;
  PointDatatype type = PointDatatype::Float32;
  bool big_endian = false;

  [[nodiscard]] double operator()(const std::uint8_t* point) const {
    const std::uint8_t* p = point + offset;
    switch (type) {
      case PointDatatype::Int8: return static_cast<std::int8_t>(p[0]);
      case PointDatatype::Uint8: return p[0];
      case PointDatatype::Int16: return static_cast<std::int16_t>(load16(p, big_endian));
      case PointDatatype::Uint16: return load16(p, big_endian);
      case PointDatatype::Int32: return static_cast<std::int32_t>(load32(p, big_endian));
      case PointDatatype::Uint32: return load32(p, big_endian);
      case PointDatatype::Float32: return static_cast<double>(std::bit_cast<float>(load32(p, big_endian)));
      case PointDatatype::Float64: return std::bit_cast<double>(load64(p, big_endian));
    }
    return 0.0;
  }
};

std::string field_names(const PointCloud2& cloud) {
  std::string s;
  for (const auto& f : cloud.fields) s += (s.empty() ? "" : " ") + f.name;
  return s.empty() ? "none" : s;
}

/// The first field of `names` the cloud has, checked to fit its point.
std::optional<FieldReader> find_field(const PointCloud2& cloud, std::initializer_list<const char*> names, const std::string& name) {
  for (const char* wanted : names) {
    for (const auto& f : cloud.fields) {
      if (f.name != wanted) continue;
      const std::size_t bytes = datatype_bytes(f.datatype);
      if (bytes == 0) throw InputError(name, 0, "field '" + f.name + "' has datatype " + std::to_string(f.datatype) + ", not 1-8");
      if (f.count == 0 || static_cast<std::uint64_t>(f.offset) + bytes > cloud.point_step) {
        throw InputError(name, 0, "field '" + f.name + "' at offset " + std::to_string(f.offset) + " does not fit a point of " +
                                      std::to_string(cloud.point_step) + " bytes");
      }
      return FieldReader{f.offset, static_cast<PointDatatype>(f.datatype), cloud.is_bigendian};
    }
  }
  return std::nullopt;
}

enum class TimeKind { RelativeNs, RelativeS, Absolute };

/// More beams than any spinning LiDAR has (the feature extractor keeps a list per ring).
constexpr double kMaxRings = 1024;

}  // namespace

PointCloud2 decode_point_cloud2(std::span<const std::uint8_t> bytes, MessageEncoding encoding, const std::string& name) {
  FieldCursor c = message_cursor(bytes, encoding, name);
  PointCloud2 m;
  m.stamp = header(c, encoding, &m.frame_id);
  m.height = c.u32("height");
  m.width = c.u32("width");
  const std::uint32_t fields = c.u32("fields length");
  for (std::uint32_t i = 0; i < fields; ++i) {  // no reserve: the length is only as good as the bytes after it
    PointField f;
    f.name = c.string("field name");
    f.offset = c.u32("field offset");
    f.datatype = c.u8("field datatype");
    f.count = c.u32("field count");
    m.fields.push_back(std::move(f));
  }
  m.is_bigendian = c.boolean("is_bigendian");
  m.point_step = c.u32("point_step");
  m.row_step = c.u32("row_step");
  m.data = c.bytes(c.u32("data length"), "data");
  m.is_dense = c.boolean("is_dense");
  expect_end(c, encoding, "sensor_msgs/PointCloud2");
  return m;
}

ImuSample decode_imu(std::span<const std::uint8_t> bytes, MessageEncoding encoding, const std::string& name) {
  FieldCursor c = message_cursor(bytes, encoding, name);
  ImuSample s;
  s.time = header(c, encoding, nullptr).seconds();
  for (int i = 0; i < 4 + 9; ++i) c.f64("orientation and its covariance");
  s.gyro = vector3(c, "angular_velocity");
  for (int i = 0; i < 9; ++i) c.f64("angular_velocity_covariance");
  s.accel = vector3(c, "linear_acceleration");
  for (int i = 0; i < 9; ++i) c.f64("linear_acceleration_covariance");
  expect_end(c, encoding, "sensor_msgs/Imu");
  if (!s.gyro.allFinite() || !s.accel.allFinite()) throw InputError(name, 0, "angular_velocity or linear_acceleration not finite");
  return s;
}

CloudSweep cloud_sweep(const PointCloud2& cloud, const std::string& name, std::uint64_t sequence, CloudConversionStats* stats) {
  const auto x = find_field(cloud, {"x"}, name), y = find_field(cloud, {"y"}, name), z = find_field(cloud, {"z"}, name);
  if (!x || !y || !z) throw InputError(name, 0, "the cloud has no x, y and z fields (fields: " + field_names(cloud) + ")");
  const auto ring = find_field(cloud, {"ring", "line"}, name);
  if (!ring) {
    throw InputError(name, 0, "the cloud has no ring or line field (fields: " + field_names(cloud) +
                                  "): liod needs each point's beam");
  }
  const auto intensity = find_field(cloud, {"intensity"}, name);
  TimeKind kind = TimeKind::RelativeNs;
  std::optional<FieldReader> time;
  for (const auto& [field, k] : {std::pair{"t", TimeKind::RelativeNs}, std::pair{"time", TimeKind::RelativeS},
                                 std::pair{"offset_time", TimeKind::RelativeNs}, std::pair{"timestamp", TimeKind::Absolute}}) {
    if ((time = find_field(cloud, {field}, name))) {
      kind = k;
      break;
    }
  }
  const std::uint64_t row_bytes = std::uint64_t{cloud.width} * cloud.point_step;
  if (cloud.width > 0 && cloud.height > 0 && (cloud.point_step == 0 || cloud.row_step < row_bytes ||
                                              std::uint64_t{cloud.height} * cloud.row_step > cloud.data.size())) {
    throw InputError(name, 0, std::to_string(cloud.height) + " rows of " + std::to_string(cloud.width) + " points of " +
                                  std::to_string(cloud.point_step) + " bytes (row_step " + std::to_string(cloud.row_step) +
                                  ") do not fit the " + std::to_string(cloud.data.size()) + " data bytes");
  }
  CloudSweep sweep;
  sweep.sequence = sequence;
  sweep.has_ring = true;
  sweep.has_time = time.has_value();
  CloudConversionStats counts;
  std::vector<double> offsets;  // each point's time after `base`, s
  sweep.points.reserve(static_cast<std::size_t>(std::uint64_t{cloud.width} * cloud.height));
  const std::uint32_t rows = cloud.width == 0 ? 0 : cloud.height;  // no points: no rows to walk, however many
  for (std::uint32_t r = 0; r < rows; ++r) {
    for (std::uint32_t k = 0; k < cloud.width; ++k) {
      const std::uint8_t* p = cloud.data.data() + std::uint64_t{r} * cloud.row_step + std::uint64_t{k} * cloud.point_step;
      LidarPoint q;
      q.x = static_cast<float>((*x)(p));
      q.y = static_cast<float>((*y)(p));
      q.z = static_cast<float>((*z)(p));
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) {
        ++counts.not_finite;
        continue;
      }
      const double b = (*ring)(p);
      if (!(b >= 0.0 && b < kMaxRings)) throw InputError(name, 0, "ring " + std::to_string(b) + " outside 0.." + std::to_string(kMaxRings - 1));
      q.ring = static_cast<std::uint16_t>(b);
      if (intensity) q.intensity = static_cast<float>((*intensity)(p));
      if (time) {
        double t = (*time)(p);
        if (kind == TimeKind::RelativeNs) t *= 1e-9;
        if (kind == TimeKind::Absolute && t > 1e14) t *= 1e-9;
        if (!std::isfinite(t)) throw InputError(name, 0, "a point's time is not finite");
        offsets.push_back(t);
      }
      sweep.points.push_back(q);
    }
  }
  sweep.start_time = kind == TimeKind::Absolute && time ? 0.0 : cloud.stamp.seconds();
  if (!offsets.empty()) {
    const auto [first, last] = std::minmax_element(offsets.begin(), offsets.end());
    const double earliest = *first;
    if (*last - earliest > 1.0) {
      throw InputError(name, 0, "per-point times span " + std::to_string(*last - earliest) + " s: not one sweep (units?)");
    }
    sweep.start_time += earliest;
    for (std::size_t i = 0; i < offsets.size(); ++i) sweep.points[i].time = static_cast<float>(offsets[i] - earliest);
  } else if (time) {
    sweep.start_time = cloud.stamp.seconds();  // every point dropped: nothing to time
  }
  if (stats != nullptr) *stats = counts;
  return sweep;
}

bool is_point_cloud2_type(const std::string& type) {
  return type == "sensor_msgs/PointCloud2" || type == "sensor_msgs/msg/PointCloud2";
}

bool is_imu_type(const std::string& type) { return type == "sensor_msgs/Imu" || type == "sensor_msgs/msg/Imu"; }

}  // namespace liod::drivers
