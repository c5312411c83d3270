#pragma once
// The drivers' configuration: the LiDAR's decoding, its UDP sockets, the IMU's transport and the
// sensors' clocks (config/liod.yaml explains each key).

#include <cstdint>
#include <string>
#include <vector>

namespace liod {

enum class LidarModel { kHelios5515, kHelios16P };
enum class CalibrationUpdates { kPin, kFollow };

struct LidarConfig {
  LidarModel model = LidarModel::kHelios5515;
  int msop_port = 6699;
  int difop_port = 7788;
  std::string angles_csv;        // fallback calibration until a DIFOP arrives; empty = wait for DIFOP
  double min_range_m = 0.1;      // decoder limits (sensor spec)
  double max_range_m = 180.0;
  double split_azimuth_deg = 0.0;
  int packets_before_difop = 4096;  // without angles_csv: MSOP held until the first DIFOP (1 s is ~1500)
  CalibrationUpdates calibration_updates = CalibrationUpdates::kPin;  // a later DIFOP's differing calibration: pin (flagged) | follow (at a sweep boundary)
};

struct LidarDriverConfig {
  std::string bind_address = "0.0.0.0";   // local IPv4 address the MSOP/DIFOP sockets bind to
  std::string multicast_group;             // "" = unicast; else an IPv4 group to join
  std::string multicast_interface = "0.0.0.0";  // local address of the interface that joins the group
  std::string source_address;              // "" = the first RS-Helios sender; else only datagrams from this IPv4 address
  int receive_buffer_bytes = 16 * 1024 * 1024;  // SO_RCVBUF(FORCE): 1 s of MSOP is ~1.9 MB
  int batch = 64;                          // datagrams per recvmmsg call
  double lost_after_s = 0.5;               // no sweep for this long flags "LiDAR lost"
};

enum class ImuTransport { kSerial, kCan, kFile, kNone };
enum class CanProfile { kJ1939, kTable };

/// One CAN signal of the `table` profile: a little/big-endian integer at a byte offset of a
/// frame, value = raw * scale + offset, in the unit liod expects (rad/s or m/s^2).
struct CanSignalConfig {
  std::string quantity;      // gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z
  std::uint32_t can_id = 0;  // 11- or 29-bit identifier (compared after masking with id_mask)
  std::uint32_t id_mask = 0x1FFFFFFF;
  int byte_offset = 0;
  int length_bytes = 2;      // 1, 2 or 4
  bool big_endian = false;
  bool is_signed = false;
  double scale = 1.0;
  double offset = 0.0;
};

struct ImuDriverConfig {
  ImuTransport transport = ImuTransport::kSerial;
  std::string serial_device = "/dev/ttyUSB0";  // Xsens MTi, MTData2 output
  int serial_baud = 921600;
  std::string can_interface = "can0";          // SocketCAN interface
  CanProfile can_profile = CanProfile::kJ1939; // J1939 PGN 61482 (rate) + 61485 (acceleration)
  int j1939_source_address = -1;               // -1 = any sender; else only this J1939 source address
  std::vector<CanSignalConfig> can_signals;    // the `table` profile's layout
  std::string file;                            // transport `file`: an IMU CSV played at `file_pace`
  double file_pace = 1.0;                      // 1 = recorded pace
  double lost_after_s = 0.1;                   // no sample for this long flags "IMU lost"
};

struct DriversConfig {
  LidarDriverConfig lidar;
  ImuDriverConfig imu;
};

enum class LidarClock { kAuto, kSensor, kHost };

struct TimeConfig {
  LidarClock lidar_clock = LidarClock::kAuto;  // auto: sensor time when DIFOP says PTP/GPS synced and it agrees with the host, else host
  double offset_window_s = 2.0;     // host-sensor offset = minimum of (arrival - header) over this window
  double jump_threshold_s = 0.1;    // an offset or host clock step beyond this is a clock jump
  double jump_flag_s = 10.0;        // poses carry the clock_jump flag this long after one
  double imu_wait_s = 0.1;          // a scan waits at most this long (host time) for the IMU to reach its end
  std::string pps_chip;             // "" = no PPS; else a GPIO chip name (e.g. gpiochip0)
  int pps_line = 0;                 // line offset of the PPS input on that chip
};

/// Everything the drivers need.
struct SensorConfig {
  LidarConfig lidar;
  DriversConfig drivers;
  TimeConfig time;
};

}  // namespace liod
