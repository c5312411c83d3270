#include "liod/drivers/kitti_raw.hpp"

#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/point_records.hpp"
#include "text_fields.hpp"

namespace liod::drivers {
namespace {

namespace fs = std::filesystem;

/// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's days_from_civil).
long long days_from_civil(long long y, unsigned m, unsigned d) {
  y -= m <= 2 ? 1 : 0;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? static_cast<unsigned>(-3) : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}

/// `len` decimal digits at `pos` (no sign: from_chars alone would take "-1" for an hour).
bool read_int(std::string_view s, std::size_t pos, std::size_t len, int& value) {
  if (pos + len > s.size()) return false;
  for (std::size_t i = pos; i < pos + len; ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
  }
  const char* first = s.data() + pos;
  const auto [ptr, ec] = std::from_chars(first, first + len, value);
  return ec == std::errc() && ptr == first + len;
}

/// The whitespace-separated numbers of a line.
std::vector<double> numbers(std::string_view line) {
  std::vector<double> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) {
      double v = 0.0;
      if (!detail::parse_double(line.substr(i, j - i), v)) return {};
      out.push_back(v);
    }
    i = j;
  }
  return out;
}

std::string frame_name(std::size_t index, const char* extension) {
  char name[32];
  std::snprintf(name, sizeof name, "%010zu%s", index, extension);
  return name;
}

}  // namespace

double parse_kitti_timestamp(std::string_view text, const std::string& file, std::size_t line) {
  text = detail::trim(text);
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  const bool ok = text.size() >= 19 && read_int(text, 0, 4, year) && text[4] == '-' && read_int(text, 5, 2, month) &&
                  text[7] == '-' && read_int(text, 8, 2, day) && text[10] == ' ' && read_int(text, 11, 2, hour) &&
                  text[13] == ':' && read_int(text, 14, 2, minute) && text[16] == ':' && read_int(text, 17, 2, second) &&
                  month >= 1 && month <= 12 && day >= 1 && day <= 31 && hour < 24 && minute < 60 && second < 61;
  double fraction = 0.0;
  const bool fraction_ok = ok && (text.size() == 19 || (text[19] == '.' && detail::parse_double(text.substr(19), fraction) &&
                                                       fraction >= 0.0 && fraction < 1.0));
  if (!ok || !fraction_ok) {
    throw InputError(file, line, "'" + std::string(text) + "' is not a timestamp YYYY-MM-DD hh:mm:ss.fffffffff");
  }
  const long long days = days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day));
  return static_cast<double>(days * 86400 + hour * 3600 + minute * 60 + second) + fraction;
}

std::vector<double> read_kitti_timestamps(const fs::path& path) {
  const std::string text = detail::read_text_file(path, "KITTI timestamps");
  detail::LineSplitter lines(text);
  std::string_view line;
  std::size_t line_no = 0;
  std::vector<double> times;
  while (lines.next(line, line_no)) {
    if (detail::trim(line).empty()) continue;
    times.push_back(parse_kitti_timestamp(line, path.string(), line_no));
  }
  return times;
}

std::vector<double> hdl64e_elevations_deg() {
  std::vector<double> e;
  for (int k = 0; k < 32; ++k) e.push_back(2.0 - k / 3.0);
  for (int k = 0; k < 32; ++k) e.push_back(-8.83 - 0.5 * k);
  return e;
}

CloudScanConfig kitti_cloud_config() {
  CloudScanConfig c;
  c.beam_elevations_deg = hdl64e_elevations_deg();
  c.start_azimuth_deg = 180.0;
  c.clockwise = false;
  return c;
}

std::vector<KittiSweepFile> read_kitti_sweep_list(const fs::path& drive) {
  const fs::path dir = drive / "velodyne_points";
  const auto starts = read_kitti_timestamps(dir / "timestamps_start.txt");
  const auto ends = read_kitti_timestamps(dir / "timestamps_end.txt");
  if (starts.size() != ends.size()) {
    throw InputError((dir / "timestamps_end.txt").string(), 0,
                     std::to_string(ends.size()) + " sweeps, but timestamps_start.txt lists " + std::to_string(starts.size()));
  }
  std::vector<KittiSweepFile> sweeps;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    KittiSweepFile s{dir / "data" / frame_name(i, ".bin"), starts[i], ends[i]};
    if (!fs::exists(s.file)) throw InputError(s.file.string(), 0, "listed in timestamps_start.txt but missing");
    if (!(ends[i] > starts[i])) throw InputError((dir / "timestamps_end.txt").string(), i + 1, "sweep ends before it starts");
    sweeps.push_back(s);
  }
  return sweeps;
}

CloudSweep read_kitti_sweep(const KittiSweepFile& sweep, std::uint64_t sequence) {
  CloudSweep s;
  s.points = read_point_records(sweep.file, kKittiVelodyneLayout);
  s.start_time = sweep.start_s;
  s.end_time = sweep.end_s;
  s.sequence = sequence;
  return s;
}

ImuSample parse_oxts_line(std::string_view line, double time, const std::string& file) {
  const std::vector<double> v = numbers(detail::trim(line));
  constexpr std::size_t kAx = 11, kWx = 17;  // ax ay az, wx wy wz: the devkit's field order
  if (v.size() < kWx + 6) throw InputError(file, 1, "expected the 30 OXTS numbers, found " + std::to_string(v.size()));
  ImuSample s;
  s.time = time;
  s.accel = Eigen::Vector3d(v[kAx], v[kAx + 1], v[kAx + 2]);
  s.gyro = Eigen::Vector3d(v[kWx], v[kWx + 1], v[kWx + 2]);
  if (!s.accel.allFinite() || !s.gyro.allFinite()) throw InputError(file, 1, "ax ay az or wx wy wz not finite");
  return s;
}

std::vector<ImuSample> read_kitti_oxts(const fs::path& drive) {
  const auto times = read_kitti_timestamps(drive / "oxts" / "timestamps.txt");
  std::vector<ImuSample> samples;
  samples.reserve(times.size());
  for (std::size_t i = 0; i < times.size(); ++i) {
    const fs::path file = drive / "oxts" / "data" / frame_name(i, ".txt");
    samples.push_back(parse_oxts_line(detail::read_text_file(file, "OXTS sample"), times[i], file.string()));
  }
  return samples;
}

Eigen::Isometry3d read_kitti_imu_to_velo(const fs::path& drive) {
  fs::path path = drive / "calib_imu_to_velo.txt";
  if (!fs::exists(path)) path = drive.parent_path() / "calib_imu_to_velo.txt";
  const std::string text = detail::read_text_file(path, "KITTI calibration");
  detail::LineSplitter lines(text);
  std::string_view line;
  std::size_t line_no = 0;
  std::vector<double> r, t;
  while (lines.next(line, line_no)) {
    line = detail::trim(line);
    if (line.rfind("R:", 0) == 0) r = numbers(line.substr(2));
    if (line.rfind("T:", 0) == 0) t = numbers(line.substr(2));
  }
  if (r.size() != 9 || t.size() != 3) throw InputError(path.string(), 0, "expected 'R:' with 9 numbers and 'T:' with 3");
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  m.translation() << t[0], t[1], t[2];
  return m;
}

}  // namespace liod::drivers
