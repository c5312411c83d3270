#include "liod/eval/oxts.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "liod/eval/io.hpp"

namespace liod::eval {
namespace {

namespace fs = std::filesystem;

fs::path oxts_folder(const std::string& path) {
  const fs::path p(path);
  return fs::exists(p / "oxts" / "timestamps.txt") ? p / "oxts" : p;
}

std::string read_first_line(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open (an OXTS sample the timestamps list)");
  std::string line;
  std::getline(in, line);
  return line;
}

/// lat, lon, alt, roll, pitch, yaw: the first six of an OXTS line's 30 numbers.
std::array<double, 6> pose_fields(const fs::path& file) {
  std::istringstream s(read_first_line(file));
  std::array<double, 6> v{};
  int n = 0;
  std::string word;
  while (s >> word) {
    char* end = nullptr;
    const double x = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(x)) {
      throw InputError(file.string() + ":1: not a number: '" + word + "'");
    }
    if (n < 6) v[static_cast<std::size_t>(n)] = x;
    ++n;
  }
  if (n < 23) throw InputError(file.string() + ":1: " + std::to_string(n) + " numbers, an OXTS line has 30");
  return v;
}

}  // namespace

bool is_oxts_dir(const std::string& path) {
  return fs::is_directory(path) && fs::exists(oxts_folder(path) / "timestamps.txt");
}

double parse_kitti_stamp(const std::string& text, const std::string& where) {
  std::tm tm{};
  int consumed = 0;
  const int got = std::sscanf(text.c_str(), "%4d-%2d-%2d %2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                              &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &consumed);
  double fraction = 0.0;
  bool ok = got == 6 && tm.tm_mon >= 1 && tm.tm_mon <= 12 && tm.tm_mday >= 1 && tm.tm_mday <= 31 && tm.tm_hour < 24 &&
            tm.tm_min < 60 && tm.tm_sec < 61;
  if (ok) {
    const std::string rest = text.substr(static_cast<std::size_t>(consumed));
    std::size_t end = rest.find_last_not_of(" \t\r");
    const std::string frac = end == std::string::npos ? std::string() : rest.substr(0, end + 1);
    if (!frac.empty()) {
      // The parsed string outlives the check of where strtod stopped in it.
      const std::string decimal = "0" + frac;
      char* stop = nullptr;
      fraction = std::strtod(decimal.c_str(), &stop);
      ok = frac.front() == '.' && *stop == '\0' && fraction < 1.0;
    }
  }
  if (!ok) throw InputError(where + ": '" + text + "' is not a time YYYY-MM-DD hh:mm:ss.fffffffff");
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<double>(timegm(&tm)) + fraction;
}

Trajectory read_oxts(const std::string& path) {
  const fs::path dir = oxts_folder(path);
  const fs::path stamps_file = dir / "timestamps.txt";
  std::ifstream in(stamps_file);
  if (!in) throw InputError(stamps_file.string() + ": cannot open (give a KITTI raw drive or its oxts/ folder)");
  Trajectory t;
  t.name = dir.string();
  std::string line;
  std::size_t line_no = 0;
  constexpr double kEarthRadius = 6378137.0;  // the devkit's er
  double scale = 0.0;
  Eigen::Isometry3d first_inv = Eigen::Isometry3d::Identity();
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const double stamp = parse_kitti_stamp(line, stamps_file.string() + ":" + std::to_string(line_no));
    if (!t.stamps.empty() && !(stamp > t.stamps.back())) {
      throw InputError(stamps_file.string() + ":" + std::to_string(line_no) + ": time does not increase");
    }
    char name[32];
    std::snprintf(name, sizeof name, "%010zu.txt", t.poses.size());
    const auto [lat, lon, alt, roll, pitch, yaw] = pose_fields(dir / "data" / name);
    if (t.poses.empty()) scale = std::cos(lat * std::numbers::pi / 180.0);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() << scale * lon * std::numbers::pi * kEarthRadius / 180.0,
        scale * kEarthRadius * std::log(std::tan((90.0 + lat) * std::numbers::pi / 360.0)), alt;
    pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                     Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
    if (t.poses.empty()) first_inv = pose.inverse();
    t.poses.push_back(first_inv * pose);
    t.stamps.push_back(stamp);
  }
  if (t.poses.empty()) throw InputError(stamps_file.string() + ": no samples");
  return t;
}

}  // namespace liod::eval
