#pragma once
// The faults liod-fault can inject, each with its parameters, and their text form
// "kind:key=value,key=value" (e.g. "drop:percent=10", "imu-cut:from=8,to=8.5"). Times are seconds
// after the recording's origin (Recording::origin_ns); LiDAR datagrams are placed in time by their
// capture (arrival) time, IMU samples by their stamp.

#include <limits>
#include <string>
#include <string_view>
#include <variant>

namespace liod::fault {

/// [from_s, to_s): the whole recording by default.
struct Window {
  double from_s = -std::numeric_limits<double>::infinity();
  double to_s = std::numeric_limits<double>::infinity();
  [[nodiscard]] bool contains(double t) const { return t >= from_s && t < to_s; }
};

/// `percent` % of the MSOP packets in the window are lost.
struct DropPackets {
  double percent = 0.0;
  Window window;
};
/// `percent` % of the MSOP packets in the window arrive late, after up to `max_shift` later ones
/// (arrival times stay in order; the contents change places).
struct ReorderPackets {
  double percent = 0.0;
  int max_shift = 3;
  Window window;
};
/// `percent` % of the MSOP packets in the window arrive twice.
struct DuplicatePackets {
  double percent = 0.0;
  Window window;
};
/// No LiDAR datagram (MSOP or DIFOP) arrives in the window.
struct StopLidar {
  Window window;
};
/// No IMU sample in the window.
struct CutImu {
  Window window;
};
/// In the window the body rocks on its springs as it does at rest when a door shuts or someone
/// climbs in: pitch and roll oscillate at 1.6 and 1.9 Hz (a car's body modes) with a peak angular
/// rate of `rate_rad_s` each. The gyro reads the rates, the accelerometer gravity tilted by the
/// angles; the LiDAR is left as it was (the angles stay below 2 mrad).
struct RockImu {
  Window window;
  double rate_rad_s = 0.02;
};
enum class Sensor { Lidar, Imu };
/// From `at_s` on, the sensor's clock reads `by_s` seconds more (negative: less). LiDAR: the
/// MSOP header time (arrival times are the host's and stay). IMU: the sample stamps; samples
/// that would not follow the previous one are dropped, as liod's IMU drivers drop them.
struct ClockJump {
  Sensor sensor = Sensor::Lidar;
  double at_s = 0.0;
  double by_s = 0.0;
};
/// What corrupted packets carry in every slot (NaN cannot be encoded in MSOP).
enum class Corruption {
  ZeroRange,  ///< range 0: "no return"
  MaxRange,   ///< range 0xFFFF: the largest the field holds (163.8 m at 2.5 mm)
  Garbage,    ///< random range and intensity bytes
};
/// `percent` % of the MSOP packets in the window have every slot corrupted.
struct CorruptPoints {
  Corruption mode = Corruption::ZeroRange;
  double percent = 100.0;
  Window window;
};
/// In the window the LiDAR sees only the ground near the vehicle: every return higher than
/// `max_z_m` in the sensor frame (range x sine of the laser's elevation) or farther than
/// `max_range_m` is blanked (range 0).
struct GroundOnly {
  Window window;
  double max_z_m = -1.5;
  double max_range_m = std::numeric_limits<double>::infinity();
};
/// The recording starts at `at_s`: earlier datagrams and samples are removed (a start while
/// the vehicle moves).
struct CutStart {
  double at_s = 0.0;
};

/// The LiDAR reboots at `at_s`: nothing for `outage_s` (an RS-Helios takes ~30 s to spin up), then
/// its packet counters start again from 0 and its clock from the unsynchronised power-on epoch
/// (the real unit's read 2017-01-06), its DIFOPs reporting no time sync.
struct LidarReboot {
  double at_s = 0.0;
  double outage_s = 30.0;
};
/// The `count` DIFOPs from `at_s` on carry a different calibration: every elevation `vertical_deg`
/// higher and, when `rpm` > 0, that motor speed (a spoofed or corrupted DIFOP, or another unit's).
struct DifopChange {
  double at_s = 0.0;
  int count = 1;
  double vertical_deg = 0.5;
  int rpm = 0;
};
/// A pothole at `at_s`: the body is thrown up and back down by a bump of the vertical position
/// h sin^2(pi t / duration), whose acceleration peaks at `peak_m_s2`; the accelerometer clips every
/// axis at `range_m_s2` (its full range), so the samples of the peaks read the range.
struct Pothole {
  double at_s = 0.0;
  double peak_m_s2 = 25.0 * 9.80665;
  double range_m_s2 = 98.07;
  double duration_s = 0.06;
};
/// In the window every block of every MSOP packet reads `azimuth_deg` (a stalled motor or a stuck
/// azimuth field): the azimuth never crosses the sweep split.
struct StuckAzimuth {
  Window window;
  double azimuth_deg = 100.0;
};
/// In the window a second host sends RS-Helios MSOP packets to the LiDAR's port: a copy of each of
/// the sensor's, from the next IPv4 address, 0.1 ms later, its azimuths turned by `shift_deg`.
struct SecondSender {
  Window window;
  double shift_deg = 180.0;
};

using Fault = std::variant<DropPackets, ReorderPackets, DuplicatePackets, StopLidar, CutImu, RockImu, ClockJump,
                           CorruptPoints, GroundOnly, CutStart, LidarReboot, DifopChange, Pothole, StuckAzimuth,
                           SecondSender>;

/// Parses the text form; throws std::invalid_argument naming the offending part.
[[nodiscard]] Fault parse_fault(std::string_view text);
/// One line per kind: its text form with every key.
[[nodiscard]] std::string fault_syntax();

}  // namespace liod::fault
