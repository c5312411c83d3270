// The HDL-64E drive in KITTI raw's layout (the "unsynced+unrectified" extract of the raw data
// readme and devkit_raw_data):
//   DATE/calib_imu_to_velo.txt                      R (9, row-major), T (3): p_velo = R p_imu + T
//   DATE/DATE_drive_NNNN_extract/velodyne_points/   data/NNNNNNNNNN.bin (float32 LE x y z reflectance),
//                                                   timestamps{,_start,_end}.txt (facing forward, start, end)
//   DATE/DATE_drive_NNNN_extract/oxts/              data/NNNNNNNNNN.txt (30 numbers), dataformat.txt,
//                                                   timestamps.txt, 100 Hz
// Times are on the IMU clock, as KITTI's recording computer stamped every stream on its own clock.

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "liod/sim/simulator.hpp"

namespace liod::sim {

namespace {
namespace fs = std::filesystem;
constexpr std::uint64_t kHdlStream = 0x68646C7377ULL;
constexpr double kOxtsRate = 100.0;
// Where the drive's first OXTS fix lies (Karlsruhe, where KITTI was recorded): the devkit's
// conversion takes its Mercator scale from the first latitude.
constexpr double kLat0Deg = 49.011;
constexpr double kLon0Deg = 8.4235;
constexpr double kAlt0M = 115.0;
constexpr double kEarthRadiusM = 6378137.0;  // the devkit's er

/// Year, month, day of a count of days since 1970-01-01 (Howard Hinnant's civil_from_days).
void civil_from_days(long long z, int& y, unsigned& m, unsigned& d) {
  z += 719468;
  const long long era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<int>(static_cast<long long>(yoe) + era * 400 + (m <= 2 ? 1 : 0));
}

/// KITTI's "YYYY-MM-DD hh:mm:ss.fffffffff" of IMU-clock time t after the epoch (UTC seconds).
std::string kitti_stamp(std::int64_t epoch_s, double t) {
  const std::int64_t ns = epoch_s * 1000000000LL + std::llround(t * 1e9);
  const std::int64_t sec = ns >= 0 ? ns / 1000000000LL : (ns - 999999999LL) / 1000000000LL;
  const std::int64_t frac = ns - sec * 1000000000LL;
  const std::int64_t days = sec >= 0 ? sec / 86400 : (sec - 86399) / 86400;
  const std::int64_t s = sec - days * 86400;
  int y = 0;
  unsigned m = 0;
  unsigned d = 0;
  civil_from_days(days, y, m, d);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02u-%02u %02" PRId64 ":%02" PRId64 ":%02" PRId64 ".%09" PRId64, y, m, d,
                s / 3600, s / 60 % 60, s % 60, frac);
  return buf;
}

std::string kitti_frame_name(std::size_t index, const char* extension) {
  char name[32];
  std::snprintf(name, sizeof name, "%010zu%s", index, extension);
  return name;
}

void write_kitti_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  if (!f) throw std::runtime_error("cannot write '" + path.string() + "'");
}

void write_bin(const fs::path& path, const std::vector<HdlPoint>& points) {
  std::vector<unsigned char> bytes(points.size() * 16);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float v[4] = {points[i].x, points[i].y, points[i].z, points[i].reflectance};
    for (int f = 0; f < 4; ++f) {
      const auto u = std::bit_cast<std::uint32_t>(v[f]);
      for (int b = 0; b < 4; ++b) bytes[i * 16 + static_cast<std::size_t>(f * 4 + b)] = static_cast<unsigned char>(u >> (8 * b));
    }
  }
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error("cannot write '" + path.string() + "'");
}

constexpr const char* kDataFormat =
    "lat:   latitude of the oxts-unit (deg)\n"
    "lon:   longitude of the oxts-unit (deg)\n"
    "alt:   altitude of the oxts-unit (m)\n"
    "roll:  roll angle (rad),    0 = level, positive = left side up,      range: -pi   .. +pi\n"
    "pitch: pitch angle (rad),   0 = level, positive = front down,        range: -pi/2 .. +pi/2\n"
    "yaw:   heading (rad),       0 = east,  positive = counter clockwise, range: -pi   .. +pi\n"
    "vn:    velocity towards north (m/s)\n"
    "ve:    velocity towards east (m/s)\n"
    "vf:    forward velocity, i.e. parallel to earth-surface (m/s)\n"
    "vl:    leftward velocity, i.e. parallel to earth-surface (m/s)\n"
    "vu:    upward velocity, i.e. perpendicular to earth-surface (m/s)\n"
    "ax:    acceleration in x, i.e. in direction of vehicle front (m/s^2)\n"
    "ay:    acceleration in y, i.e. in direction of vehicle left (m/s^2)\n"
    "az:    acceleration in z, i.e. in direction of vehicle top (m/s^2)\n"
    "af:    forward acceleration (m/s^2)\n"
    "al:    leftward acceleration (m/s^2)\n"
    "au:    upward acceleration (m/s^2)\n"
    "wx:    angular rate around x (rad/s)\n"
    "wy:    angular rate around y (rad/s)\n"
    "wz:    angular rate around z (rad/s)\n"
    "wf:    angular rate around forward axis (rad/s)\n"
    "wl:    angular rate around leftward axis (rad/s)\n"
    "wu:    angular rate around upward axis (rad/s)\n"
    "pos_accuracy:  position accuracy (north/east in m)\n"
    "vel_accuracy:  velocity accuracy (north/east in m/s)\n"
    "navstat:       navigation status (see navstat_to_string)\n"
    "numsats:       number of satellites tracked by primary GPS receiver\n"
    "posmode:       position mode of primary GPS receiver (see gps_mode_to_string)\n"
    "velmode:       velocity mode of primary GPS receiver (see gps_mode_to_string)\n"
    "orimode:       orientation mode of primary GPS receiver (see gps_mode_to_string)\n";

/// One OXTS line: the true pose and velocity of the IMU (the unit's RTK/INS solution, taken as
/// exact), and the IMU's own measured rates and specific force, in the vehicle's axes (x y z)
/// and in the levelled heading frame (f l u: the same vectors turned by roll and pitch).
std::string oxts_line(const BodyState& s, const ImuReading& r, const Eigen::Vector3d& first) {
  const Eigen::Matrix3d& R = s.rotation;  // R = Rz(yaw) Ry(pitch) Rx(roll), world x east, y north
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double pitch = -std::asin(std::clamp(R(2, 0), -1.0, 1.0));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const Eigen::Matrix3d level_from_body = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix().transpose() * R;
  const Eigen::Vector3d af = level_from_body * r.accel;
  const Eigen::Vector3d wf = level_from_body * r.gyro;
  const Eigen::Vector2d v_level = Eigen::Rotation2Dd(-yaw) * s.velocity.head<2>();
  // The inverse of the devkit's latlonToMercator, its scale from the first fix's latitude.
  const double scale = std::cos(kLat0Deg * std::numbers::pi / 180.0);
  const double mx0 = scale * kLon0Deg * std::numbers::pi * kEarthRadiusM / 180.0;
  const double my0 = scale * kEarthRadiusM * std::log(std::tan((90.0 + kLat0Deg) * std::numbers::pi / 360.0));
  const double mx = mx0 + (s.position.x() - first.x());
  const double my = my0 + (s.position.y() - first.y());
  const double lon = mx * 180.0 / (std::numbers::pi * kEarthRadiusM * scale);
  const double lat = 360.0 / std::numbers::pi * std::atan(std::exp(my / (scale * kEarthRadiusM))) - 90.0;
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "%.14f %.14f %.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f "
                "%.9f %.9f %.9f %.9f %.9f %.9f 0.02 0.01 4 10 4 4 4\n",
                lat, lon, kAlt0M + s.position.z() - first.z(), roll, pitch, yaw, s.velocity.y(), s.velocity.x(),
                v_level.x(), v_level.y(), s.velocity.z(), r.accel.x(), r.accel.y(), r.accel.z(), af.x(), af.y(), af.z(),
                r.gyro.x(), r.gyro.y(), r.gyro.z(), wf.x(), wf.y(), wf.z());
  return buf;
}
}  // namespace

std::string kitti_raw_drive(const SimConfig& config) {
  const std::string day = kitti_stamp(config.epoch_s, 0.0).substr(0, 10);
  std::string date = day;
  std::replace(date.begin(), date.end(), '-', '_');
  char drive[32];
  std::snprintf(drive, sizeof drive, "_drive_%04u_extract", static_cast<unsigned>(config.scene.seed % 10000U));
  return (fs::path(config.kitti_dir.empty() ? config.out_dir : config.kitti_dir) / date / (date + drive)).string();
}

RunReport Simulation::write_kitti_raw(const std::function<void(double)>& progress) const {
  const fs::path drive(kitti_raw_drive(config_));
  for (const char* dir : {"velodyne_points/data", "oxts/data"}) fs::create_directories(drive / dir);
  // calib_imu_to_velo.txt: the IMU's frame into the Velodyne's, the inverse of imu_from_lidar.
  const Eigen::Matrix3d R = imu_from_lidar_.rotation.transpose();
  const Eigen::Vector3d T = -(R * imu_from_lidar_.translation);
  char calib[512];
  std::snprintf(calib, sizeof calib,
                "calib_time: %s\nR: %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e %.12e\nT: %.12e %.12e %.12e\n",
                kitti_stamp(config_.epoch_s, 0.0).substr(0, 19).c_str(), R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1),
                R(1, 2), R(2, 0), R(2, 1), R(2, 2), T.x(), T.y(), T.z());
  write_kitti_text(drive.parent_path() / "calib_imu_to_velo.txt", calib);
  RunReport report;
  write_kitti_sweeps(drive.string(), report, progress);
  write_oxts(drive.string());
  return report;
}

void Simulation::write_kitti_sweeps(const std::string& drive, RunReport& report,
                                    const std::function<void(double)>& progress) const {
  const fs::path dir = fs::path(drive) / "velodyne_points";
  // Turns begin facing backward; the first at the seed's LiDAR phase, the last ending within the drive.
  const double t_first = time_offset_;
  const auto sweeps = static_cast<std::uint64_t>(std::floor((config_.scene.duration - t_first) / kHdlTurnPeriod - 1e-9));
  const int threads = std::max(1, config_.threads);
  const auto batch = static_cast<std::uint64_t>(threads) * 2;
  std::string starts, ends, middles;
  std::vector<std::vector<HdlPoint>> points(static_cast<std::size_t>(batch));
  std::vector<std::uint64_t> rays(static_cast<std::size_t>(batch));
  const auto pose_at = [this](double t) { return lidar_pose(t); };
  for (std::uint64_t k0 = 0; k0 < sweeps; k0 += batch) {
    const std::uint64_t n = std::min(batch, sweeps - k0);
    auto work = [&](int tid) {
      for (std::uint64_t k = static_cast<std::uint64_t>(tid); k < n; k += static_cast<std::uint64_t>(threads)) {
        RayContext ctx(scene_.world, derive_seed(config_.scene.seed, kHdlStream, k0 + k));
        rays[static_cast<std::size_t>(k)] = 0;
        hdl_->sweep(t_first + kHdlTurnPeriod * static_cast<double>(k0 + k), pose_at, scene_.world, ctx,
                    points[static_cast<std::size_t>(k)], &rays[static_cast<std::size_t>(k)]);
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& th : pool) th.join();
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::uint64_t index = k0 + k;
      const double t0 = t_first + kHdlTurnPeriod * static_cast<double>(index);
      write_bin(dir / "data" / kitti_frame_name(index, ".bin"), points[static_cast<std::size_t>(k)]);
      starts += kitti_stamp(config_.epoch_s, t0) + "\n";
      ends += kitti_stamp(config_.epoch_s, t0 + kHdlTurnPeriod) + "\n";
      middles += kitti_stamp(config_.epoch_s, t0 + 0.5 * kHdlTurnPeriod) + "\n";
      report.returns += points[static_cast<std::size_t>(k)].size();
      report.rays += rays[static_cast<std::size_t>(k)];
      ++report.sweeps;
    }
    if (progress) progress(static_cast<double>(k0 + n) / static_cast<double>(sweeps));
  }
  write_kitti_text(dir / "timestamps_start.txt", starts);
  write_kitti_text(dir / "timestamps_end.txt", ends);
  write_kitti_text(dir / "timestamps.txt", middles);
}

void Simulation::write_oxts(const std::string& drive) const {
  const fs::path dir = fs::path(drive) / "oxts";
  write_kitti_text(dir / "dataformat.txt", kDataFormat);
  // The same IMU as imu.csv's (same stream, same rate): the OXTS extract is 100 Hz.
  ImuModel model(imu_noise_, kOxtsRate, derive_seed(config_.scene.seed, kImuStream));
  const auto n = static_cast<std::int64_t>(std::floor(config_.scene.duration * kOxtsRate + 1e-9));
  const Eigen::Vector3d first = trajectory_->state(0.0).position;
  std::string stamps;
  for (std::int64_t k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / kOxtsRate;
    const BodyState s = trajectory_->state(t);
    const ImuReading r = model.measure(s);
    write_kitti_text(dir / "data" / kitti_frame_name(static_cast<std::size_t>(k), ".txt"), oxts_line(s, r, first));
    stamps += kitti_stamp(config_.epoch_s, t) + "\n";
  }
  write_kitti_text(dir / "timestamps.txt", stamps);
}

}  // namespace liod::sim
