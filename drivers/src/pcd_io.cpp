#include "liod/drivers/pcd_io.hpp"
#include "liod/drivers/c_file.hpp"

#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"
#include "text_fields.hpp"

namespace liod::drivers {
namespace {

constexpr std::size_t kPointRecordBytes = 5 * 4 + 2;

struct FieldSpec {
  std::string name;
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
};

std::vector<std::string_view> split_words(std::string_view s) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t' && s[i] != '\r') ++i;
    if (i > start) words.push_back(s.substr(start, i - start));
  }
  return words;
}

std::size_t parse_count(std::string_view word, const std::string& file, std::size_t line) {
  std::size_t v = 0;
  const auto [ptr, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || ptr != word.data() + word.size())
    throw InputError(file, line, "'" + std::string(word) + "' is not a count");
  return v;
}

double decode_binary(const std::uint8_t* p, const FieldSpec& f) {
  // PCD binary bodies are little-endian in practice (PCL writes host order; every host it runs
  // on is little-endian); decode explicitly so a big-endian host would still read them right.
  switch (f.type) {
    case 'F':
      if (f.size == 4) return static_cast<double>(std::bit_cast<float>(load_le32(p)));
      if (f.size == 8) return std::bit_cast<double>((std::uint64_t{load_le32(p + 4)} << 32) | load_le32(p));
      break;
    case 'U':
      if (f.size == 1) return p[0];
      if (f.size == 2) return load_le16(p);
      if (f.size == 4) return load_le32(p);
      if (f.size == 8) return static_cast<double>((std::uint64_t{load_le32(p + 4)} << 32) | load_le32(p));
      break;
    case 'I':
      if (f.size == 1) return static_cast<std::int8_t>(p[0]);
      if (f.size == 2) return static_cast<std::int16_t>(load_le16(p));
      if (f.size == 4) return static_cast<std::int32_t>(load_le32(p));
      if (f.size == 8) return static_cast<double>(static_cast<std::int64_t>((std::uint64_t{load_le32(p + 4)} << 32) | load_le32(p)));
      break;
    default:
      break;
  }
  return 0.0;
}

}  // namespace

void write_pcd_binary(const std::filesystem::path& path, const Scan& scan) {
  const std::string name = path.string();
  CFile f(std::fopen(name.c_str(), "wb"));
  if (!f) throw InputError(name, 0, std::string("cannot create PCD file: ") + std::strerror(errno));
  const std::size_t n = scan.points.size();
  char header[768];
  const int len = std::snprintf(header, sizeof header,
                                "# .PCD v0.7 - Point Cloud Data file format\n"
                                "# liod scan sequence=%llu start_time=%.9f end_time=%.9f beam_count=%u\n"
                                "VERSION 0.7\n"
                                "FIELDS x y z intensity time ring\n"
                                "SIZE 4 4 4 4 4 2\n"
                                "TYPE F F F F F U\n"
                                "COUNT 1 1 1 1 1 1\n"
                                "WIDTH %zu\n"
                                "HEIGHT 1\n"
                                "VIEWPOINT 0 0 0 1 0 0 0\n"
                                "POINTS %zu\n"
                                "DATA binary\n",
                                static_cast<unsigned long long>(scan.sequence), scan.start_time, scan.end_time,
                                static_cast<unsigned>(scan.beam_count), n, n);
  if (len < 0 || static_cast<std::size_t>(len) >= sizeof header ||
      std::fwrite(header, 1, static_cast<std::size_t>(len), f.get()) != static_cast<std::size_t>(len))
    throw InputError(name, 0, "cannot write PCD header");
  std::vector<std::uint8_t> body(n * kPointRecordBytes);
  std::uint8_t* p = body.data();
  for (const LidarPoint& pt : scan.points) {
    store_le32(p, std::bit_cast<std::uint32_t>(pt.x));
    store_le32(p + 4, std::bit_cast<std::uint32_t>(pt.y));
    store_le32(p + 8, std::bit_cast<std::uint32_t>(pt.z));
    store_le32(p + 12, std::bit_cast<std::uint32_t>(pt.intensity));
    store_le32(p + 16, std::bit_cast<std::uint32_t>(pt.time));
    store_le16(p + 20, pt.ring);
    p += kPointRecordBytes;
  }
  // fwrite's buffer must not be null even for 0 bytes (an empty scan has no body).
  if (!body.empty() && std::fwrite(body.data(), 1, body.size(), f.get()) != body.size())
    throw InputError(name, 0, std::string("write failed: ") + std::strerror(errno));
  if (std::fclose(f.release()) != 0) throw InputError(name, 0, std::string("close failed: ") + std::strerror(errno));
}

int PcdCloud::field_index(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (fields[i] == name) return static_cast<int>(i);
  return -1;
}

PcdCloud read_pcd(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(file, 0, "cannot open PCD file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();

  std::vector<FieldSpec> specs;
  std::size_t points = 0;
  bool have_points = false;
  PcdCloud cloud;
  std::string data;
  std::size_t pos = 0;
  std::size_t line_no = 0;
  while (pos < text.size() && data.empty()) {
    const std::size_t end = text.find('\n', pos);
    const std::string_view line(text.data() + pos, (end == std::string::npos ? text.size() : end) - pos);
    pos = end == std::string::npos ? text.size() : end + 1;
    ++line_no;
    const std::vector<std::string_view> w = split_words(line);
    if (w.empty() || w[0].front() == '#') continue;
    const std::string_view key = w[0];
    const auto per_field = [&](auto&& apply) {
      if (w.size() - 1 != specs.size())
        throw InputError(file, line_no, std::string(key) + " has " + std::to_string(w.size() - 1) + " entries for " +
                                            std::to_string(specs.size()) + " fields");
      for (std::size_t i = 1; i < w.size(); ++i) apply(specs[i - 1], w[i]);
    };
    if (key == "FIELDS") {
      specs.clear();
      for (std::size_t i = 1; i < w.size(); ++i) specs.push_back(FieldSpec{std::string(w[i])});
    } else if (key == "SIZE") {
      per_field([&](FieldSpec& f, std::string_view v) { f.size = parse_count(v, file, line_no); });
    } else if (key == "TYPE") {
      per_field([&](FieldSpec& f, std::string_view v) {
        if (v.size() != 1 || (v[0] != 'F' && v[0] != 'U' && v[0] != 'I'))
          throw InputError(file, line_no, "unknown PCD type '" + std::string(v) + "'");
        f.type = v[0];
      });
    } else if (key == "COUNT") {
      per_field([&](FieldSpec& f, std::string_view v) { f.count = parse_count(v, file, line_no); });
    } else if (key == "WIDTH" && w.size() == 2) {
      cloud.width = parse_count(w[1], file, line_no);
    } else if (key == "HEIGHT" && w.size() == 2) {
      cloud.height = parse_count(w[1], file, line_no);
    } else if (key == "POINTS" && w.size() == 2) {
      points = parse_count(w[1], file, line_no);
      have_points = true;
    } else if (key == "DATA" && w.size() == 2) {
      data = std::string(w[1]);
    }
  }
  if (specs.empty()) throw InputError(file, 0, "PCD header has no FIELDS line");
  if (data.empty()) throw InputError(file, 0, "PCD header has no DATA line");
  if (!have_points) points = cloud.width * (cloud.height == 0 ? 1 : cloud.height);

  std::size_t columns = 0;
  std::size_t record_bytes = 0;
  for (const FieldSpec& f : specs) {
    for (std::size_t c = 0; c < f.count; ++c)
      cloud.fields.push_back(c == 0 ? f.name : f.name + "_" + std::to_string(c));
    columns += f.count;
    record_bytes += f.size * f.count;
  }
  cloud.values.resize(points * columns);

  if (data == "ascii") {
    std::size_t point = 0;
    while (pos < text.size() && point < points) {
      const std::size_t end = text.find('\n', pos);
      const std::string_view line(text.data() + pos, (end == std::string::npos ? text.size() : end) - pos);
      pos = end == std::string::npos ? text.size() : end + 1;
      ++line_no;
      const std::vector<std::string_view> w = split_words(line);
      if (w.empty()) continue;
      if (w.size() != columns)
        throw InputError(file, line_no, "expected " + std::to_string(columns) + " values, found " + std::to_string(w.size()));
      for (std::size_t c = 0; c < columns; ++c) {
        double v = 0.0;
        if (!detail::parse_double(w[c], v))
          throw InputError(file, line_no, "'" + std::string(w[c]) + "' is not a number");
        cloud.values[point * columns + c] = v;
      }
      ++point;
    }
    if (point != points)
      throw InputError(file, line_no, "file ends after " + std::to_string(point) + " of " + std::to_string(points) + " points");
  } else if (data == "binary") {
    if (text.size() - pos < points * record_bytes)
      throw InputError(file, 0, "binary body holds " + std::to_string((text.size() - pos) / record_bytes) + " of " +
                                    std::to_string(points) + " points");
    const auto* p = reinterpret_cast<const std::uint8_t*>(text.data() + pos);
    for (std::size_t i = 0; i < points; ++i) {
      std::size_t c = 0;
      for (const FieldSpec& f : specs) {
        for (std::size_t k = 0; k < f.count; ++k, ++c, p += f.size) cloud.values[i * columns + c] = decode_binary(p, f);
      }
    }
  } else {
    throw InputError(file, line_no, "unsupported PCD DATA '" + data + "' (ascii and binary are supported)");
  }
  return cloud;
}

std::vector<PcdPoint> read_pcd_points(const std::filesystem::path& path) {
  const PcdCloud cloud = read_pcd(path);
  const int ix = cloud.field_index("x");
  const int iy = cloud.field_index("y");
  const int iz = cloud.field_index("z");
  if (ix < 0 || iy < 0 || iz < 0) throw InputError(path.string(), 0, "PCD file has no x y z fields");
  int ii = cloud.field_index("intensity");
  int ic = cloud.field_index("channel");
  if (ic < 0) ic = cloud.field_index("ring");
  int it = cloud.field_index("time_stamp");
  if (it < 0) it = cloud.field_index("timestamp");
  if (it < 0) it = cloud.field_index("time");
  std::vector<PcdPoint> out(cloud.points());
  for (std::size_t i = 0; i < out.size(); ++i) {
    PcdPoint& p = out[i];
    p.x = static_cast<float>(cloud.value(i, static_cast<std::size_t>(ix)));
    p.y = static_cast<float>(cloud.value(i, static_cast<std::size_t>(iy)));
    p.z = static_cast<float>(cloud.value(i, static_cast<std::size_t>(iz)));
    if (ii >= 0) p.intensity = static_cast<float>(cloud.value(i, static_cast<std::size_t>(ii)));
    if (ic >= 0) p.channel = static_cast<std::uint16_t>(cloud.value(i, static_cast<std::size_t>(ic)));
    if (it >= 0) p.time_stamp = cloud.value(i, static_cast<std::size_t>(it));
  }
  return out;
}

}  // namespace liod::drivers
