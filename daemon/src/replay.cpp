#include "liod/daemon/replay.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <unistd.h>

#include "liod/daemon/trajectory_writer.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/lidar_inertial_odometry.hpp"

namespace liod {
namespace {

drivers::HeliosOptions helios_options(const Config& config) {
  drivers::HeliosOptions o;
  o.model = config.lidar.model == LidarModel::kHelios16P ? drivers::HeliosModel::Helios16P : drivers::HeliosModel::Helios5515;
  if (!config.lidar.angles_csv.empty()) o.angles = drivers::load_angles_csv(config.lidar.angles_csv);
  o.msop.min_range_m = static_cast<float>(config.lidar.min_range_m);
  o.msop.max_range_m = static_cast<float>(config.lidar.max_range_m);
  o.split_azimuth_deg = config.lidar.split_azimuth_deg;
  return o;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

class ProgressBar {
 public:
  ProgressBar(bool enabled, std::uintmax_t total) : enabled_(enabled && isatty(STDERR_FILENO)), total_(total) {}
  void update(std::uintmax_t done, std::size_t scans) {
    if (!enabled_ || total_ == 0) return;
    const int percent = static_cast<int>(100.0 * static_cast<double>(done) / static_cast<double>(total_));
    if (percent == last_) return;
    last_ = percent;
    const int width = 40;
    const int filled = percent * width / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%  %zu scans", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), percent, scans);
  }
  void finish() {
    if (enabled_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::uintmax_t total_;
  int last_ = -1;
};

}  // namespace

int run_replay(const Config& config, const ReplayOptions& options, std::ostream& out) {
  const auto wall_start = std::chrono::steady_clock::now();
  drivers::PcapReader pcap(options.pcap);
  pcap.set_port_filter({static_cast<std::uint16_t>(config.lidar.msop_port), static_cast<std::uint16_t>(config.lidar.difop_port)});
  drivers::ImuCsvReader imu(options.imu_csv);
  LidarInertialOdometry odometry(config);
  TrajectoryWriter trajectory(options.trajectory_tum);
  std::unique_ptr<TrajectoryWriter> imu_rate;
  if (!options.imu_rate_tum.empty()) imu_rate = std::make_unique<TrajectoryWriter>(options.imu_rate_tum);
  std::ofstream scan_log;
  if (!options.scan_log_csv.empty()) {
    scan_log.open(options.scan_log_csv);
    if (!scan_log) throw std::runtime_error(options.scan_log_csv + ": cannot open for writing");
    scan_log << "time,status,points,edges,planes,residuals,iterations,rms_m,min_eigenvalue,hausdorff_m,"
                "deskew_ms,features_ms,registration_ms,map_ms\n";
  }

  std::deque<Scan> pending;
  drivers::RsHeliosDecoder decoder(helios_options(config), [&](Scan& scan, const drivers::SweepInfo&) {
    pending.push_back(std::move(scan));
  });

  ImuSample sample;
  bool imu_left = imu.next(sample);
  std::size_t imu_count = 0;
  auto feed_imu_until = [&](double time) {
    while (imu_left && sample.time <= time) {
      odometry.add_imu(sample);
      ++imu_count;
      if (imu_rate) {
        if (const auto s = odometry.propagated_state()) imu_rate->write(*s);
      }
      imu_left = imu.next(sample);
    }
  };

  std::vector<double> front_end_ms;
  std::size_t scans = 0;
  std::size_t processed = 0;
  std::size_t degenerate = 0;
  std::size_t keyframes = 0;
  const auto total_bytes = std::filesystem::file_size(options.pcap);
  ProgressBar progress(options.progress, total_bytes);
  std::uintmax_t bytes = 0;

  auto process_ready = [&](bool final) {
    while (!pending.empty()) {
      const double end = odometry.scan_end_time(pending.front());
      // A scan needs the IMU to reach its end; at the end of the log it gets what there is.
      feed_imu_until(end + 0.02);
      if (!final && imu_left && odometry.latest_imu_time() < end) return;
      ++scans;
      const auto result = odometry.process(pending.front());
      pending.pop_front();
      if (!result) continue;
      ++processed;
      const double ms = result->deskew_ms + result->features_ms + result->registration_ms;
      front_end_ms.push_back(ms);
      if (result->status & kStatusDegenerate) ++degenerate;
      if (result->status & kStatusKeyframe) ++keyframes;
      trajectory.write(result->state);
      if (scan_log) {
        scan_log << std::fixed << std::setprecision(6) << result->state.time << ',' << result->status << ','
                 << result->points << ',' << result->edge_features << ',' << result->plane_features << ','
                 << result->residuals << ',' << result->iterations << ',' << std::setprecision(4)
                 << result->rms_residual_m << ',' << result->min_translation_eigenvalue << ','
                 << result->hausdorff_m << ',' << result->deskew_ms << ',' << result->features_ms << ','
                 << result->registration_ms << ',' << result->map_ms << '\n';
      }
    }
  };

  drivers::UdpDatagram datagram;
  while (pcap.next(datagram)) {
    bytes += datagram.payload.size() + 58;
    decoder.feed(datagram.payload, datagram.capture_time_ns);
    process_ready(false);
    progress.update(bytes, scans);
  }
  decoder.flush();
  process_ready(true);
  progress.update(total_bytes, scans);
  progress.finish();

  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const auto& ps = pcap.stats();
  const auto hs = decoder.stats();
  if (!pcap.error().empty()) spdlog::warn("{}: {}", options.pcap, pcap.error());
  out << "replay: " << scans << " scans (" << processed << " with a pose, " << keyframes << " keyframes, " << degenerate
      << " degenerate), " << imu_count << " IMU samples (" << odometry.dropped_imu_samples() << " dropped)\n";
  out << "packets: " << hs.msop << " MSOP, " << hs.difop << " DIFOP, " << hs.rejected() << " rejected, "
      << ps.dropped() << " dropped by the pcap reader\n";
  out << std::fixed << std::setprecision(2) << "front end per scan (deskew + features + registration): median "
      << percentile(front_end_ms, 0.5) << " ms, p99 " << percentile(front_end_ms, 0.99) << " ms\n";
  const double drive_s = scans > 0 ? static_cast<double>(scans) * 0.1 : 0.0;
  out << "wall time " << wall_s << " s for " << drive_s << " s of data (" << (wall_s > 0 ? drive_s / wall_s : 0.0)
      << "x real time)\n";
  out << "trajectory: " << options.trajectory_tum << '\n';
  if (processed == 0) {
    spdlog::error("no pose was estimated: check that the IMU log and the pcap cover the same time span");
    return 1;
  }
  return 0;
}

}  // namespace liod
