#pragma once
// The decoded Ouster recording (shared/data/ouster: an OS1 pcap decoded by its
// decode_ouster_pcap.py): the sensor's metadata JSON, frames.csv listing each sweep's .bin of
// x, y, z, reflectivity, time records in the Ouster "sensor" frame, and imu.csv from the sensor's
// own IMU on the same clock. Read into the point-cloud path (cloud_sweep.hpp).

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "liod/drivers/cloud_sweep.hpp"
#include "liod/types.hpp"

namespace liod::drivers {

/// What liod needs of an Ouster sensor's metadata JSON (transforms in metres).
struct OusterMetadata {
  std::vector<double> beam_altitude_deg;
  double beam_origin_offset_m = 0.0;  ///< lidar_origin_to_beam_origin_mm
  Eigen::Isometry3d lidar_to_sensor = Eigen::Isometry3d::Identity();  ///< the spinning head in the sensor frame
  Eigen::Isometry3d imu_to_sensor = Eigen::Isometry3d::Identity();
  /// liod's extrinsic for points in the sensor frame: p_imu = lidar_to_imu * p_sensor.
  Eigen::Isometry3d sensor_to_imu() const { return imu_to_sensor.inverse(); }
  /// The cloud path's settings for sensor-frame points: this head's beams and geometry.
  CloudScanConfig cloud_config() const;
};

/// Throws InputError naming the file and the key that is missing or malformed.
OusterMetadata read_ouster_metadata(const std::filesystem::path& path);

struct OusterFrame {
  std::uint64_t frame_id = 0;
  double first_column_s = 0.0;  ///< sensor clock
  double last_column_s = 0.0;
  std::filesystem::path file;   ///< the frame's .bin, resolved against the list's folder
};

/// frames.csv (index,frame_id,n_points,t_first_col_ns,t_last_col_ns,file). InputError on a bad row.
std::vector<OusterFrame> read_ouster_frame_list(const std::filesystem::path& path);
/// One frame's points as a sweep with per-point time and no ring.
CloudSweep read_ouster_frame(const OusterFrame& frame, std::uint64_t sequence);
/// imu.csv (t_accel_ns,t_gyro_ns, accel m/s^2, gyro rad/s), stamped with the gyro's time.
std::vector<ImuSample> read_ouster_imu(const std::filesystem::path& path);

}  // namespace liod::drivers
