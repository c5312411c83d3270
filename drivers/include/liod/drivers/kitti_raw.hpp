#pragma once
// KITTI raw drives (the unsynced "extract" layout of the KITTI devkit's raw data readme):
//   DRIVE/velodyne_points/data/NNNNNNNNNN.bin   float32 x, y, z, reflectance per return
//   DRIVE/velodyne_points/timestamps{,_start,_end}.txt   one "YYYY-MM-DD hh:mm:ss.fffffffff" a sweep
//   DRIVE/oxts/data/NNNNNNNNNN.txt   30 numbers a line (lat lon alt roll pitch yaw vn ve vf vl vu
//                                    ax ay az af al au wx wy wz wf wl wu ...), 100 Hz
//   DRIVE/oxts/timestamps.txt
//   calib_imu_to_velo.txt (in DRIVE or its parent, the date folder): R (9), T (3): p_velo = R p_imu + T
// Sweeps go through the point-cloud path with an HDL-64E beam table (no ring, no per-point time
// in the files); the OXTS unit's body-frame rates and accelerations are the IMU.

#include <Eigen/Geometry>
#include <filesystem>
#include <string_view>
#include <vector>

#include "liod/drivers/cloud_sweep.hpp"
#include "liod/types.hpp"

namespace liod::drivers {

/// A KITTI timestamp line as seconds since 1970-01-01 (the calendar's, no time zone: the files
/// carry none, and only differences matter). InputError naming `file` and `line` when malformed.
double parse_kitti_timestamp(std::string_view text, const std::string& file, std::size_t line);
std::vector<double> read_kitti_timestamps(const std::filesystem::path& path);

/// The Velodyne HDL-64E's nominal beam elevations: the upper block's 32 lasers from +2 to -8.33
/// deg a third of a degree apart, the lower block's from -8.83 to -24.33 half a degree apart
/// (Velodyne's HDL-64E S2 manual). A unit's own calibration differs by up to a few tenths.
std::vector<double> hdl64e_elevations_deg();

/// The point-cloud path's settings for KITTI's sweeps: the HDL-64E table; each sweep begins and
/// ends facing backward and the head turns counter-clockwise (the raw data readme).
CloudScanConfig kitti_cloud_config();

struct KittiSweepFile {
  std::filesystem::path file;
  double start_s = 0.0;
  double end_s = 0.0;
};

/// The drive's sweeps in order, with their start and end times. InputError when the timestamp
/// files disagree in length with each other or a listed .bin is missing.
std::vector<KittiSweepFile> read_kitti_sweep_list(const std::filesystem::path& drive);
CloudSweep read_kitti_sweep(const KittiSweepFile& sweep, std::uint64_t sequence);

/// The OXTS samples as IMU samples: the vehicle-axis rates and accelerations wx wy wz, ax ay az
/// (x forward, y left, z up; the accelerations are specific force, +9.81 up at rest). Not kitti2bag's
/// wf wl wu, af al au: those are the same vectors in the levelled heading frame (the dataformat's
/// "parallel to earth-surface"), which turns with roll and pitch against the body and so against
/// the Velodyne that calib_imu_to_velo.txt fixes to the body. On a simulated urban drive the
/// levelled fields cost 0.97 deg of constant attitude error against 0.28 deg (docs/results.md).
std::vector<ImuSample> read_kitti_oxts(const std::filesystem::path& drive);
/// One OXTS line's sample (`time` given); InputError unless it has at least 23 numbers.
ImuSample parse_oxts_line(std::string_view line, double time, const std::string& file);

/// calib_imu_to_velo.txt's transform (p_velo = R p_imu + T), from DRIVE or its parent.
Eigen::Isometry3d read_kitti_imu_to_velo(const std::filesystem::path& drive);

}  // namespace liod::drivers
