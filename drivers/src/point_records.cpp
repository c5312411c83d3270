#include "liod/drivers/point_records.hpp"

#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

float load_le_float(const std::uint8_t* p) noexcept { return std::bit_cast<float>(load_le32(p)); }

}  // namespace

std::vector<LidarPoint> parse_point_records(std::span<const std::uint8_t> bytes, const PointRecordLayout& layout,
                                            const std::string& name) {
  if (layout.fields < (layout.has_time ? 5U : 4U)) throw std::invalid_argument("point record layout: too few fields");
  const std::size_t record = 4 * layout.fields;
  const std::size_t whole = bytes.size() / record;
  if (bytes.size() % record != 0) {
    throw InputError(name, 0, "truncated point record at byte offset " + std::to_string(whole * record) + ": " +
                                  std::to_string(bytes.size() % record) + " bytes of a " + std::to_string(record) +
                                  "-byte record (" + std::to_string(layout.fields) + " float32 fields)");
  }
  std::vector<LidarPoint> points(whole);
  for (std::size_t i = 0; i < whole; ++i) {
    const std::uint8_t* r = bytes.data() + i * record;
    LidarPoint& p = points[i];
    p.x = load_le_float(r);
    p.y = load_le_float(r + 4);
    p.z = load_le_float(r + 8);
    p.intensity = load_le_float(r + 12);
    if (layout.has_time) {
      p.time = load_le_float(r + 16);
      if (!std::isfinite(p.time) || p.time < 0.0F) {
        throw InputError(name, 0, "point time " + std::to_string(p.time) + " s at byte offset " +
                                      std::to_string(i * record + 16) + " is not a finite time after the sweep's start");
      }
    }
  }
  return points;
}

std::vector<LidarPoint> read_point_records(const std::filesystem::path& path, const PointRecordLayout& layout) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), 0, "cannot open point file");
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError(path.string(), 0, "read failed");
  return parse_point_records(bytes, layout, path.string());
}

}  // namespace liod::drivers
