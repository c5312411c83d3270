#pragma once
// The pipeline's sources: live (UDP LiDAR, serial MTData2 IMU, SocketCAN IMU) and files (pcap,
// IMU CSV) at recorded pace, a multiple of it, or as fast as possible.

#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/drivers/pcap_reader.hpp"

namespace liod {

/// A data time in seconds as the pace clock's nanoseconds.
inline std::int64_t to_ns(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

/// Shared by the file sources of one replay so they keep their recorded relative timing:
/// data time `t` is released at host time start + (t - data_start) / pace.
struct PaceClock {
  double pace = 0.0;               ///< 0 = as fast as possible
  std::int64_t data_start_ns = 0;
  std::int64_t host_start_steady_ns = 0;
  /// A datum due further than this from now (a recorded pause, a capture time years off) moves
  /// the clock so that it is due now: the replay neither sleeps for years nor races the rest.
  std::int64_t max_offset_ns = 10'000'000'000;
  /// Sleeps (in bounded steps, calling `heartbeat`) until `data_ns` is due. False if stopped.
  bool wait_until(std::int64_t data_ns, const std::atomic<bool>& stop, const std::function<void()>& heartbeat) const;
  /// How often the clock was moved for a datum beyond max_offset_ns.
  std::uint64_t reanchors() const noexcept { return reanchors_.load(std::memory_order_relaxed); }

 private:
  mutable std::atomic<std::int64_t> shift_ns_{0};
  mutable std::atomic<std::uint64_t> reanchors_{0};
};

class PcapLidarSource : public LidarSource {
 public:
  PcapLidarSource(std::string path, std::vector<std::uint16_t> ports, std::shared_ptr<const PaceClock> pace);
  void run(LidarOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return "pcap " + path_; }
  /// Valid after run() returned.
  const drivers::PcapStats& stats() const { return stats_; }
  const std::string& read_error() const { return error_; }
  std::uintmax_t bytes_read() const { return bytes_.load(); }

 private:
  std::string path_;
  std::vector<std::uint16_t> ports_;
  std::shared_ptr<const PaceClock> pace_;
  drivers::PcapStats stats_;
  std::string error_;
  std::atomic<std::uintmax_t> bytes_{0};
};

class UdpLidarSource : public LidarSource {
 public:
  explicit UdpLidarSource(const Config& config);
  void run(LidarOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override;

 private:
  const Config& config_;
};

class CsvImuSource : public ImuSource {
 public:
  CsvImuSource(std::string path, std::shared_ptr<const PaceClock> pace);
  void run(ImuOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return "IMU log " + path_; }

 private:
  std::string path_;
  std::shared_ptr<const PaceClock> pace_;
};

class SerialImuSource : public ImuSource {
 public:
  explicit SerialImuSource(const Config& config);
  void run(ImuOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override;

 private:
  const Config& config_;
};

class CanImuSource : public ImuSource {
 public:
  explicit CanImuSource(const Config& config);
  void run(ImuOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override;

 private:
  const Config& config_;
};

/// First timestamp (ns) of a pcap (its first delivered datagram) and of an IMU CSV; 0 if empty.
std::int64_t first_pcap_time_ns(const std::string& path, const std::vector<std::uint16_t>& ports);
std::int64_t first_imu_time_ns(const std::string& path);

/// The live sources the configuration asks for (`liod run` / `liod record`).
std::unique_ptr<LidarSource> make_live_lidar_source(const Config& config);
std::unique_ptr<ImuSource> make_live_imu_source(const Config& config);

}  // namespace liod
