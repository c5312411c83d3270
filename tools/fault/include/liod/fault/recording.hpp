#pragma once
// A recorded drive held in memory so that faults can rewrite it: the UDP datagrams of the LiDAR
// capture (MSOP and DIFOP, in file order) and the IMU log. Read and written with liod_drivers'
// own pcap and IMU CSV code, so the result replays exactly like a recording made by `liod record`.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "liod/types.hpp"

namespace liod::fault {

struct Packet {
  std::int64_t capture_time_ns = 0;  ///< host (arrival) time
  std::uint32_t src_ip = 0;
  std::uint32_t dst_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::vector<std::uint8_t> payload;
};

struct Recording {
  std::vector<Packet> packets;
  std::vector<ImuSample> imu;
  /// Start of the recording (earliest capture time or IMU stamp), ns on the host clock. Fault
  /// times are seconds after it; it is fixed when the recording is read, so that faults applied
  /// one after another share one time base.
  std::int64_t origin_ns = 0;

  /// Seconds after the origin of a capture time / an IMU stamp.
  [[nodiscard]] double seconds_of(std::int64_t capture_time_ns) const {
    return static_cast<double>(capture_time_ns - origin_ns) * 1e-9;
  }
  [[nodiscard]] double seconds_of_imu(double imu_time_s) const {
    return imu_time_s - static_cast<double>(origin_ns) * 1e-9;
  }
};

/// Reads every UDP datagram of `pcap` (any port) and every sample of `imu_csv`; throws
/// drivers::InputError on unreadable input.
Recording read_recording(const std::filesystem::path& pcap, const std::filesystem::path& imu_csv);

/// Writes the datagrams (nanosecond pcap) and the samples (IMU CSV); throws on a write error.
void write_recording(const Recording& recording, const std::filesystem::path& pcap, const std::filesystem::path& imu_csv);

}  // namespace liod::fault
