#pragma once
// Writes ROS 1 bags (format 2.0: bag header padded to 4 KiB, chunks of connection and message
// records followed by their index data, then every connection and the chunk infos at index_pos)
// and MCAP files (magic, Header, Chunks holding Schema, Channel and Message records with their
// CRC, Data End, a summary of Schemas and Channels, Footer, magic), with sensor_msgs/PointCloud2
// in the point layouts of the Velodyne, Ouster, Hesai and Livox ROS drivers and sensor_msgs/Imu,
// in ROS 1 serialization or CDR of either byte order: what the bag tests read and the fuzz seeds
// start from. Written from the formats' specifications, not from liod's readers.

#include <bzlib.h>
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "liod/drivers/byte_order.hpp"
#include "liod/types.hpp"

namespace liod::test {

using Bytes = std::vector<std::uint8_t>;

enum class Serialization { Ros1, CdrLittle, CdrBig };

/// Appends fields the way ROS 1 (packed, little-endian) or CDR (aligned from the payload's start,
/// strings with their NUL) lays them out.
class Serializer {
 public:
  explicit Serializer(Serialization s) : s_(s) {
    if (s == Serialization::CdrLittle) out_ = {0x00, 0x01, 0x00, 0x00};
    if (s == Serialization::CdrBig) out_ = {0x00, 0x00, 0x00, 0x00};
    origin_ = out_.size();
  }
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u32(std::uint32_t v) {
    align(4);
    const std::size_t at = grow(4);
    if (big()) drivers::store_be32(&out_[at], v);
    else drivers::store_le32(&out_[at], v);
  }
  void f64(double v) {
    align(8);
    const std::size_t at = grow(8);
    if (big()) drivers::store_be64(&out_[at], std::bit_cast<std::uint64_t>(v));
    else drivers::store_le64(&out_[at], std::bit_cast<std::uint64_t>(v));
  }
  void string(const std::string& text) {
    const bool cdr = s_ != Serialization::Ros1;
    u32(static_cast<std::uint32_t>(text.size() + (cdr ? 1 : 0)));
    out_.insert(out_.end(), text.begin(), text.end());
    if (cdr) out_.push_back(0);
  }
  void bytes(const Bytes& b) {
    u32(static_cast<std::uint32_t>(b.size()));
    out_.insert(out_.end(), b.begin(), b.end());
  }
  /// std_msgs/Header (ROS 1 with its seq).
  void header(std::int64_t sec, std::uint32_t nsec, const std::string& frame) {
    if (s_ == Serialization::Ros1) u32(0);
    u32(static_cast<std::uint32_t>(sec));
    u32(nsec);
    string(frame);
  }
  Bytes take() { return std::move(out_); }

 private:
  bool big() const { return s_ == Serialization::CdrBig; }
  void align(std::size_t n) {
    if (s_ == Serialization::Ros1) return;
    while ((out_.size() - origin_) % n != 0) out_.push_back(0);
  }
  std::size_t grow(std::size_t n) {
    out_.resize(out_.size() + n);
    return out_.size() - n;
  }
  Serialization s_;
  Bytes out_;
  std::size_t origin_ = 0;
};

/// A ROS stamp from seconds: whole seconds and the nearest nanosecond.
struct Stamp {
  std::int64_t sec = 0;
  std::uint32_t nsec = 0;
  static Stamp of(double t) {
    Stamp s;
    s.sec = static_cast<std::int64_t>(std::floor(t));
    auto ns = std::llround((t - static_cast<double>(s.sec)) * 1e9);
    if (ns >= 1'000'000'000) {
      ++s.sec;
      ns -= 1'000'000'000;
    }
    s.nsec = static_cast<std::uint32_t>(ns);
    return s;
  }
  std::int64_t ns() const { return sec * 1'000'000'000 + nsec; }
};

/// The point layouts of the ROS drivers (field, offset, datatype per sensor_msgs/PointField).
enum class CloudLayout {
  Velodyne,  ///< x y z f32, intensity f32 @16, ring u16 @20, time f32 (s after the stamp) @24; 32 bytes
  Ouster,    ///< x y z f32, intensity f32 @16, t u32 (ns after the stamp) @20, reflectivity u16, ring u16 @26, ...; 48 bytes
  Hesai,     ///< x y z f32, intensity u8 @16, timestamp f64 (s since the epoch) @24, ring u16 @32; 40 bytes
  Livox,     ///< x y z f32, intensity f32 @12, tag u8 @16, line u8 @17, offset_time u32 (ns) @18; 22 bytes, packed
  NoTime,    ///< x y z f32, intensity f32, ring u16: no per-point time; 18 bytes
};

struct CloudOptions {
  CloudLayout layout = CloudLayout::Velodyne;
  Serialization serialization = Serialization::Ros1;
  bool big_endian_points = false;  ///< is_bigendian: the point fields big-endian
  std::uint32_t height = 1;        ///< rows (an organized cloud); the points divide evenly
  std::uint32_t row_padding = 0;   ///< bytes after each row (row_step > width * point_step)
};

struct FieldSpec {
  const char* name;
  std::uint32_t offset;
  std::uint8_t datatype;
};

inline std::vector<FieldSpec> cloud_fields(CloudLayout layout, std::uint32_t& point_step) {
  switch (layout) {
    case CloudLayout::Velodyne:
      point_step = 32;
      return {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 16, 7}, {"ring", 20, 4}, {"time", 24, 7}};
    case CloudLayout::Ouster:
      point_step = 48;
      return {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 16, 7}, {"t", 20, 6}, {"reflectivity", 24, 4},
              {"ring", 26, 4}, {"ambient", 28, 4}, {"range", 32, 6}};
    case CloudLayout::Hesai:
      point_step = 40;
      return {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 16, 2}, {"timestamp", 24, 8}, {"ring", 32, 4}};
    case CloudLayout::Livox:
      point_step = 22;
      return {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 12, 7}, {"tag", 16, 2}, {"line", 17, 2}, {"offset_time", 18, 6}};
    case CloudLayout::NoTime:
      point_step = 18;
      return {{"x", 0, 7}, {"y", 4, 7}, {"z", 8, 7}, {"intensity", 12, 7}, {"ring", 16, 4}};
  }
  return {};
}

/// A scan's points as a PointCloud2 stamped `stamp` (the sweep's start, per-point times after it).
inline Bytes serialize_cloud(const Scan& scan, Stamp stamp, const CloudOptions& o) {
  std::uint32_t step = 0;
  const auto fields = cloud_fields(o.layout, step);
  const auto width = static_cast<std::uint32_t>(scan.points.size() / o.height);
  if (static_cast<std::size_t>(width) * o.height != scan.points.size()) throw std::invalid_argument("rows do not divide the points");
  const std::uint32_t row_step = width * step + o.row_padding;
  Bytes data(static_cast<std::size_t>(row_step) * o.height, 0xA5);  // padding bytes are not zero
  const bool be = o.big_endian_points;
  auto put32 = [&](std::size_t at, std::uint32_t v) { be ? drivers::store_be32(&data[at], v) : drivers::store_le32(&data[at], v); };
  auto put16 = [&](std::size_t at, std::uint16_t v) { be ? drivers::store_be16(&data[at], v) : drivers::store_le16(&data[at], v); };
  auto putf = [&](std::size_t at, float v) { put32(at, std::bit_cast<std::uint32_t>(v)); };
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    const std::size_t at = (i / width) * row_step + (i % width) * step;
    putf(at, p.x);
    putf(at + 4, p.y);
    putf(at + 8, p.z);
    const auto ns = static_cast<std::uint32_t>(std::llround(static_cast<double>(p.time) * 1e9));
    switch (o.layout) {
      case CloudLayout::Velodyne:
        putf(at + 16, p.intensity);
        put16(at + 20, p.ring);
        putf(at + 24, p.time);
        break;
      case CloudLayout::Ouster:
        putf(at + 16, p.intensity);
        put32(at + 20, ns);
        put16(at + 26, p.ring);
        break;
      case CloudLayout::Hesai: {
        data[at + 16] = static_cast<std::uint8_t>(std::clamp(p.intensity, 0.0F, 255.0F));
        const double t = stamp.sec + stamp.nsec * 1e-9 + static_cast<double>(p.time);
        const auto bits = std::bit_cast<std::uint64_t>(t);
        be ? drivers::store_be64(&data[at + 24], bits) : drivers::store_le64(&data[at + 24], bits);
        put16(at + 32, p.ring);
        break;
      }
      case CloudLayout::Livox:
        putf(at + 12, p.intensity);
        data[at + 17] = static_cast<std::uint8_t>(p.ring);
        put32(at + 18, ns);
        break;
      case CloudLayout::NoTime:
        putf(at + 12, p.intensity);
        put16(at + 16, p.ring);
        break;
    }
  }
  Serializer s(o.serialization);
  s.header(stamp.sec, stamp.nsec, "lidar");
  s.u32(o.height);
  s.u32(width);
  s.u32(static_cast<std::uint32_t>(fields.size()));
  for (const auto& f : fields) {
    s.string(f.name);
    s.u32(f.offset);
    s.u8(f.datatype);
    s.u32(1);
  }
  s.u8(be ? 1 : 0);
  s.u32(step);
  s.u32(row_step);
  s.bytes(data);
  s.u8(1);
  return s.take();
}

inline Bytes serialize_imu(const ImuSample& imu, Serialization serialization) {
  Serializer s(serialization);
  const Stamp stamp = Stamp::of(imu.time);
  s.header(stamp.sec, stamp.nsec, "imu");
  for (const double q : {0.0, 0.0, 0.0, 1.0}) s.f64(q);
  for (int i = 0; i < 9; ++i) s.f64(i == 0 ? -1.0 : 0.0);  // orientation not estimated (REP 145)
  for (int i = 0; i < 3; ++i) s.f64(imu.gyro[i]);
  for (int i = 0; i < 9; ++i) s.f64(0.0);
  for (int i = 0; i < 3; ++i) s.f64(imu.accel[i]);
  for (int i = 0; i < 9; ++i) s.f64(0.0);
  return s.take();
}

// ---- containers ---------------------------------------------------------------------------------

struct TopicSpec {
  std::string name;
  std::string type;  ///< ROS 1 name ("sensor_msgs/Imu"); MCAP gets the ROS 2 name ("sensor_msgs/msg/Imu")
};

struct MessageSpec {
  std::size_t topic = 0;  ///< index into the topics
  std::int64_t time_ns = 0;
  Bytes data;
};

inline Bytes compress(const std::string& codec, const Bytes& in) {
  if (codec.empty() || codec == "none") return in;
  Bytes out;
  if (codec == "bz2") {
    auto n = static_cast<unsigned>(in.size() + in.size() / 100 + 600);
    out.resize(n);
    if (BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &n, const_cast<char*>(reinterpret_cast<const char*>(in.data())),
                                 static_cast<unsigned>(in.size()), 9, 0, 0) != BZ_OK) {
      throw std::runtime_error("bz2 compression failed");
    }
    out.resize(n);
  } else if (codec == "lz4") {
    LZ4F_preferences_t prefs{};
    prefs.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;  // as roslz4 writes its frames
    out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
    const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
    if (LZ4F_isError(n)) throw std::runtime_error("lz4 compression failed");
    out.resize(n);
  } else if (codec == "zstd") {
    out.resize(ZSTD_compressBound(in.size()));
    const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3);
    if (ZSTD_isError(n)) throw std::runtime_error("zstd compression failed");
    out.resize(n);
  } else {
    throw std::invalid_argument("unknown codec " + codec);
  }
  return out;
}

namespace bag_detail {

inline void le32(Bytes& b, std::uint32_t v) {
  b.resize(b.size() + 4);
  drivers::store_le32(&b[b.size() - 4], v);
}
inline void le64(Bytes& b, std::uint64_t v) {
  b.resize(b.size() + 8);
  drivers::store_le64(&b[b.size() - 8], v);
}
inline void field(Bytes& header, const std::string& name, const Bytes& value) {
  le32(header, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
  header.insert(header.end(), name.begin(), name.end());
  header.push_back('=');
  header.insert(header.end(), value.begin(), value.end());
}
inline Bytes u32_bytes(std::uint32_t v) {
  Bytes b;
  le32(b, v);
  return b;
}
inline Bytes u64_bytes(std::uint64_t v) {
  Bytes b;
  le64(b, v);
  return b;
}
inline Bytes text(const std::string& s) { return {s.begin(), s.end()}; }
inline Bytes ros_time(std::int64_t ns) {
  Bytes b;
  le32(b, static_cast<std::uint32_t>(ns / 1'000'000'000));
  le32(b, static_cast<std::uint32_t>(ns % 1'000'000'000));
  return b;
}
inline void record(Bytes& out, const Bytes& header, const Bytes& data) {
  le32(out, static_cast<std::uint32_t>(header.size()));
  out.insert(out.end(), header.begin(), header.end());
  le32(out, static_cast<std::uint32_t>(data.size()));
  out.insert(out.end(), data.begin(), data.end());
}
inline Bytes connection_header(const TopicSpec& t) {
  Bytes h;
  field(h, "topic", text(t.name));
  field(h, "type", text(t.type));
  field(h, "md5sum", text("*"));
  field(h, "message_definition", text(""));
  return h;
}
inline void connection_record(Bytes& out, std::uint32_t id, const TopicSpec& t) {
  Bytes h;
  field(h, "op", {0x07});
  field(h, "conn", u32_bytes(id));
  field(h, "topic", text(t.name));
  record(out, h, connection_header(t));
}

}  // namespace bag_detail

struct Ros1BagOptions {
  std::string compression = "none";  ///< none, bz2, lz4
  std::size_t chunk_bytes = 768 * 1024;  ///< rosbag's default chunk threshold
  bool indexed = true;  ///< false: index_pos 0 and no index section, as a recording cut short leaves it
};

/// A ROS 1 bag of `messages` (in the order given) on `topics`.
inline Bytes write_ros1_bag(const std::vector<TopicSpec>& topics, const std::vector<MessageSpec>& messages, const Ros1BagOptions& o = {}) {
  using namespace bag_detail;
  Bytes out = text("#ROSBAG V2.0\n");
  const std::size_t bag_header_at = out.size();
  out.resize(out.size() + 4096);  // written last, once index_pos is known
  struct ChunkInfo {
    std::uint64_t pos;
    std::int64_t start, end;
    std::map<std::uint32_t, std::uint32_t> counts;
  };
  std::vector<ChunkInfo> infos;
  std::vector<bool> written(topics.size(), false);
  std::size_t next = 0;
  while (next < messages.size()) {
    Bytes records;
    ChunkInfo info{out.size(), messages[next].time_ns, messages[next].time_ns, {}};
    std::map<std::uint32_t, std::vector<std::pair<std::int64_t, std::uint32_t>>> index;
    while (next < messages.size() && records.size() < o.chunk_bytes) {
      const MessageSpec& m = messages[next++];
      const auto conn = static_cast<std::uint32_t>(m.topic);
      if (!written[m.topic]) {
        connection_record(records, conn, topics[m.topic]);
        written[m.topic] = true;
      }
      index[conn].emplace_back(m.time_ns, static_cast<std::uint32_t>(records.size()));
      Bytes h;
      field(h, "op", {0x02});
      field(h, "conn", u32_bytes(conn));
      field(h, "time", ros_time(m.time_ns));
      record(records, h, m.data);
      info.start = std::min(info.start, m.time_ns);
      info.end = std::max(info.end, m.time_ns);
      ++info.counts[conn];
    }
    Bytes h;
    field(h, "op", {0x05});
    field(h, "compression", text(o.compression));
    field(h, "size", u32_bytes(static_cast<std::uint32_t>(records.size())));
    record(out, h, compress(o.compression, records));
    for (const auto& [conn, entries] : index) {
      Bytes ih, data;
      field(ih, "op", {0x04});
      field(ih, "ver", u32_bytes(1));
      field(ih, "conn", u32_bytes(conn));
      field(ih, "count", u32_bytes(static_cast<std::uint32_t>(entries.size())));
      for (const auto& [t, offset] : entries) {
        const Bytes tb = ros_time(t);
        data.insert(data.end(), tb.begin(), tb.end());
        le32(data, offset);
      }
      record(out, ih, data);
    }
    infos.push_back(info);
  }
  const std::uint64_t index_pos = o.indexed ? out.size() : 0;
  if (o.indexed) {
    for (std::size_t i = 0; i < topics.size(); ++i) connection_record(out, static_cast<std::uint32_t>(i), topics[i]);
    for (const auto& info : infos) {
      Bytes h, data;
      field(h, "op", {0x06});
      field(h, "ver", u32_bytes(1));
      field(h, "chunk_pos", u64_bytes(info.pos));
      field(h, "start_time", ros_time(info.start));
      field(h, "end_time", ros_time(info.end));
      field(h, "count", u32_bytes(static_cast<std::uint32_t>(info.counts.size())));
      for (const auto& [conn, count] : info.counts) {
        le32(data, conn);
        le32(data, count);
      }
      record(out, h, data);
    }
  }
  Bytes h;
  field(h, "op", {0x03});
  field(h, "index_pos", u64_bytes(index_pos));
  field(h, "conn_count", u32_bytes(static_cast<std::uint32_t>(topics.size())));
  field(h, "chunk_count", u32_bytes(static_cast<std::uint32_t>(infos.size())));
  Bytes bag_header;
  record(bag_header, h, Bytes(4096 - 8 - h.size(), ' '));  // padded to 4 KiB, as rosbag does
  std::copy(bag_header.begin(), bag_header.end(), out.begin() + static_cast<std::ptrdiff_t>(bag_header_at));
  return out;
}

struct McapOptions {
  std::string compression;  ///< "", lz4, zstd
  std::size_t chunk_bytes = 768 * 1024;
  bool summary = true;  ///< false: no summary section (footer's summary_start 0)
  std::string message_encoding = "cdr";
};

/// An MCAP file of `messages` on `topics` (types given in ROS 1 form, written in ROS 2's).
inline Bytes write_mcap(const std::vector<TopicSpec>& topics, const std::vector<MessageSpec>& messages, const McapOptions& o = {}) {
  using namespace bag_detail;
  const Bytes magic{0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
  auto op_record = [](Bytes& out, std::uint8_t op, const Bytes& content) {
    out.push_back(op);
    le64(out, content.size());
    out.insert(out.end(), content.begin(), content.end());
  };
  auto str = [](Bytes& b, const std::string& s) {
    le32(b, static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
  };
  auto ros2_type = [](const std::string& t) {
    const auto slash = t.find('/');
    return slash == std::string::npos ? t : t.substr(0, slash) + "/msg" + t.substr(slash);
  };
  auto schema = [&](Bytes& out, std::size_t i) {
    Bytes c;
    c.resize(2);
    drivers::store_le16(c.data(), static_cast<std::uint16_t>(i + 1));
    str(c, ros2_type(topics[i].type));
    str(c, "ros2msg");
    str(c, "");
    op_record(out, 0x03, c);
  };
  auto channel = [&](Bytes& out, std::size_t i) {
    Bytes c(4);
    drivers::store_le16(c.data(), static_cast<std::uint16_t>(i));
    drivers::store_le16(c.data() + 2, static_cast<std::uint16_t>(i + 1));
    str(c, topics[i].name);
    str(c, o.message_encoding);
    le32(c, 0);  // metadata: an empty map
    op_record(out, 0x04, c);
  };
  Bytes out = magic;
  Bytes header;
  str(header, "ros2");
  str(header, "liod-test");
  op_record(out, 0x01, header);
  std::vector<bool> written(topics.size(), false);
  std::size_t next = 0;
  while (next < messages.size()) {
    Bytes records;
    const std::int64_t start = messages[next].time_ns;
    std::int64_t end = start;
    while (next < messages.size() && records.size() < o.chunk_bytes) {
      const MessageSpec& m = messages[next++];
      if (!written[m.topic]) {
        schema(records, m.topic);
        channel(records, m.topic);
        written[m.topic] = true;
      }
      Bytes c(2);
      drivers::store_le16(c.data(), static_cast<std::uint16_t>(m.topic));
      le32(c, static_cast<std::uint32_t>(next));
      le64(c, static_cast<std::uint64_t>(m.time_ns));
      le64(c, static_cast<std::uint64_t>(m.time_ns));
      c.insert(c.end(), m.data.begin(), m.data.end());
      op_record(records, 0x05, c);
      end = std::max(end, m.time_ns);
    }
    Bytes c;
    le64(c, static_cast<std::uint64_t>(start));
    le64(c, static_cast<std::uint64_t>(end));
    le64(c, records.size());
    le32(c, static_cast<std::uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), records.data(), static_cast<uInt>(records.size()))));
    str(c, o.compression);
    const Bytes stored = compress(o.compression, records);
    le64(c, stored.size());
    c.insert(c.end(), stored.begin(), stored.end());
    op_record(out, 0x06, c);
  }
  op_record(out, 0x0F, u32_bytes(0));
  const std::uint64_t summary_start = o.summary ? out.size() : 0;
  if (o.summary) {
    for (std::size_t i = 0; i < topics.size(); ++i) schema(out, i);
    for (std::size_t i = 0; i < topics.size(); ++i) channel(out, i);
  }
  Bytes footer;
  le64(footer, summary_start);
  le64(footer, 0);
  le32(footer, 0);
  op_record(out, 0x02, footer);
  out.insert(out.end(), magic.begin(), magic.end());
  return out;
}

}  // namespace liod::test
