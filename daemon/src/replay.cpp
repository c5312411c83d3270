#include "liod/daemon/replay.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "liod/daemon/bag_sources.hpp"
#include "liod/daemon/foxglove_server.hpp"
#include "liod/daemon/kitti_sources.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/daemon/trajectory_writer.hpp"

#include "liod/daemon/percentile.hpp"
#include "liod/drivers/kitti_raw.hpp"

namespace liod {
namespace {

class ProgressBar {
 public:
  ProgressBar(bool enabled, std::uintmax_t total) : enabled_(enabled && isatty(STDERR_FILENO)), total_(total) {}
  void update(std::uintmax_t done, std::uint64_t scans) {
    if (!enabled_ || total_ == 0) return;
    const int percent = static_cast<int>(100.0 * static_cast<double>(std::min(done, total_)) / static_cast<double>(total_));
    if (percent == last_) return;
    last_ = percent;
    const int width = 40;
    const int filled = percent * width / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%  %llu scans", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), percent,
                 static_cast<unsigned long long>(scans));
  }
  void finish() {
    if (enabled_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::uintmax_t total_;
  int last_ = -1;
};

/// The per-scan CSV (--scan-log): status, features, timings and the filter's state.
class ScanLog {
 public:
  explicit ScanLog(const std::string& path) : path_(path) {
    if (path.empty()) return;
    out_.open(path);
    if (!out_) throw std::runtime_error(path + ": cannot open for writing");
    out_ << "time,status,points,edges,planes,residuals,iterations,rms_m,min_eigenvalue,hausdorff_m,"
            "deskew_ms,features_ms,registration_ms,map_ms,"
            "velocity_x,velocity_y,velocity_z,velocity_correction_x,velocity_correction_y,velocity_correction_z,"
            "accel_bias_x,accel_bias_y,accel_bias_z,gyro_bias_x,gyro_bias_y,gyro_bias_z,"
            "gravity_x,gravity_y,gravity_z,forward_hold\n";
  }
  void write(double time, const ScanDiagnostics& d) {
    if (!out_.is_open() || !out_) return;  // after a failed write the stream writes nothing more
    out_ << std::fixed << std::setprecision(6) << time << ',' << d.status << ',' << d.points << ',' << d.edges << ','
         << d.planes << ',' << d.residuals << ',' << d.iterations << ',' << std::setprecision(4) << d.rms_m << ','
         << d.min_eigenvalue << ',' << d.hausdorff_m << ',' << d.deskew_ms << ',' << d.features_ms << ','
         << d.registration_ms << ',' << d.map_ms << std::setprecision(6);
    for (const Eigen::Vector3d* v : {&d.velocity_body, &d.velocity_correction_body, &d.accel_bias, &d.gyro_bias, &d.gravity_body}) {
      out_ << ',' << v->x() << ',' << v->y() << ',' << v->z();
    }
    out_ << ',' << (d.forward_hold ? 1 : 0) << '\n';
  }
  /// Flushes and closes; "" or what failed.
  std::string close() {
    if (!out_.is_open()) return "";
    out_.flush();
    const bool good = static_cast<bool>(out_);
    const int error_number = errno;
    out_.close();
    return good ? "" : path_ + ": write failed: " + std::strerror(error_number);
  }

 private:
  std::string path_;
  std::ofstream out_;
};

/// Closes every output file; prints (and logs) each one that failed. True when all are complete.
bool close_outputs(TrajectoryWriter& trajectory, TrajectoryWriter* imu_rate, TrajectoryWriter* map_frame, ScanLog& scan_log,
                   std::ostream& out) {
  std::vector<std::string> errors;
  for (TrajectoryWriter* w : {&trajectory, imu_rate, map_frame}) {
    if (w != nullptr && !w->close()) errors.push_back(w->error() + " (the file is incomplete)");
  }
  if (const std::string e = scan_log.close(); !e.empty()) errors.push_back(e);
  for (const auto& e : errors) {
    out << "error: " << e << '\n';
    spdlog::error("{}", e);
  }
  return errors.empty();
}

/// The replay's LiDAR input: packets from a pcap, a KITTI raw drive's sweeps, or a bag's clouds.
struct LidarInput {
  std::unique_ptr<LidarSource> source;
  std::function<std::uintmax_t()> done;  // progress, against total
  std::uintmax_t total = 0;
  std::function<void(std::ostream&)> report;  // the summary's input line
  std::function<void()> warn;                 // after the run: what the reader could not read
};

LidarInput pcap_input(Pipeline& pipeline, const ReplayOptions& options, const std::vector<std::uint16_t>& ports,
                      const std::shared_ptr<PaceClock>& pace) {
  auto source = std::make_unique<PcapLidarSource>(options.pcap, ports, pace);
  PcapLidarSource* pcap = source.get();
  LidarInput in;
  in.source = std::move(source);
  in.done = [pcap] { return pcap->bytes_read(); };
  in.total = std::filesystem::file_size(options.pcap);
  in.report = [pcap, &pipeline](std::ostream& out) {
    const auto& ps = pcap->stats();
    const auto hs = pipeline.lidar_output().decoder_stats();
    out << "packets: " << hs.msop << " MSOP, " << hs.difop << " DIFOP, " << hs.rejected() << " rejected, "
        << ps.dropped() << " dropped by the pcap reader\n";
  };
  in.warn = [pcap, path = options.pcap] {
    if (!pcap->read_error().empty()) spdlog::warn("{}: {}", path, pcap->read_error());
  };
  return in;
}

LidarInput kitti_input(const ReplayOptions& options, const std::shared_ptr<PaceClock>& pace) {
  auto source = std::make_unique<KittiLidarSource>(options.kitti_raw, pace);
  KittiLidarSource* kitti = source.get();
  LidarInput in;
  in.source = std::move(source);
  in.done = [kitti] { return kitti->sweeps_read(); };
  in.total = drivers::read_kitti_sweep_list(options.kitti_raw).size();
  in.report = [kitti](std::ostream& out) {
    out << "sweeps: " << kitti->sweeps_read() << " of " << kitti->sweeps_total() << " read, "
        << kitti->returns_dropped() << " returns off every HDL-64E beam or too near\n";
  };
  in.warn = [] {};
  return in;
}

LidarInput bag_input(const ReplayOptions& options, const std::shared_ptr<PaceClock>& pace) {
  auto source = std::make_unique<BagLidarSource>(options.bag, options.lidar_topic, pace);
  BagLidarSource* bag = source.get();
  LidarInput in;
  in.source = std::move(source);
  in.done = [bag] { return bag->sweeps_read(); };
  in.total = 0;  // unknown without reading the file through: no progress bar
  in.report = [bag, topic = options.lidar_topic](std::ostream& out) {
    out << "sweeps: " << bag->sweeps_read() << " read from " << topic << ", " << bag->points_dropped()
        << " points not finite or too near\n";
  };
  in.warn = [] {};
  return in;
}

LidarInput lidar_input(Pipeline& pipeline, const ReplayOptions& options, const std::vector<std::uint16_t>& ports,
                       const std::shared_ptr<PaceClock>& pace) {
  if (!options.kitti_raw.empty()) return kitti_input(options, pace);
  if (!options.bag.empty()) return bag_input(options, pace);
  return pcap_input(pipeline, options, ports, pace);
}

std::unique_ptr<ImuSource> imu_input(const ReplayOptions& options, const std::shared_ptr<PaceClock>& pace) {
  if (!options.kitti_raw.empty()) return std::make_unique<KittiImuSource>(options.kitti_raw, pace);
  if (!options.bag.empty()) return std::make_unique<BagImuSource>(options.bag, options.imu_topic, pace);
  return std::make_unique<CsvImuSource>(options.imu_csv, pace);
}

/// Where the pace clock starts: the earlier of the inputs' first stamps (the later one when the
/// other has none).
std::int64_t data_start_ns(const ReplayOptions& options, const std::vector<std::uint16_t>& ports) {
  std::int64_t t_lidar = 0, t_imu = 0;
  if (!options.kitti_raw.empty()) {
    t_lidar = first_kitti_sweep_ns(options.kitti_raw);
    t_imu = first_kitti_imu_ns(options.kitti_raw);
  } else if (!options.bag.empty()) {
    t_lidar = first_bag_cloud_ns(options.bag, options.lidar_topic);
    t_imu = first_bag_imu_ns(options.bag, options.imu_topic);
  } else {
    t_lidar = first_pcap_time_ns(options.pcap, ports);
    t_imu = first_imu_time_ns(options.imu_csv);
  }
  return (t_lidar == 0 || t_imu == 0) ? std::max(t_lidar, t_imu) : std::min(t_lidar, t_imu);
}

/// The configuration with the KITTI drive's calib_imu_to_velo.txt as its extrinsics.
Config with_kitti_extrinsics(const Config& config, const std::string& drive) {
  Config c = config;
  const Eigen::Isometry3d velo_to_imu = drivers::read_kitti_imu_to_velo(drive).inverse();
  c.extrinsics.lidar_to_imu_rotation = Eigen::Quaterniond(velo_to_imu.linear()).normalized();
  c.extrinsics.lidar_to_imu_translation = velo_to_imu.translation();
  return c;
}

void print_summary(Pipeline& pipeline, const LidarInput& input, double wall_s, std::ostream& out) {
  const auto& t = pipeline.totals();
  out << "replay: " << t.scans << " scans (" << t.processed << " with a pose, " << t.keyframes << " keyframes, "
      << t.degenerate << " degenerate), " << t.imu_fed << " IMU samples ("
      << t.imu_dropped + pipeline.imu_output().out_of_range() << " dropped, " << pipeline.imu_output().out_of_range()
      << " of them beyond the measurement range; " << pipeline.imu_output().saturated() << " saturated)\n";
  input.report(out);
  out << std::fixed << std::setprecision(2) << "front end per scan (deskew + features + registration): median "
      << percentile(t.front_end_ms, 0.5) << " ms, p99 " << percentile(t.front_end_ms, 0.99) << " ms\n";
  const double drive_s = t.scans > 0 ? static_cast<double>(t.scans) * 0.1 : 0.0;
  out << "wall time " << wall_s << " s for " << drive_s << " s of data (" << (wall_s > 0 ? drive_s / wall_s : 0.0)
      << "x real time)\n";
}

}  // namespace

int run_replay(const Config& given, const ReplayOptions& options, std::ostream& out) {
  const auto wall_start = std::chrono::steady_clock::now();
  const bool kitti = !options.kitti_raw.empty();
  if (!options.bag.empty()) check_bag_topics(options.bag, options.lidar_topic, options.imu_topic);
  const Config config = kitti ? with_kitti_extrinsics(given, options.kitti_raw) : given;
  const std::vector<std::uint16_t> ports{static_cast<std::uint16_t>(config.lidar.msop_port),
                                         static_cast<std::uint16_t>(config.lidar.difop_port)};
  // Both file sources share one pace clock anchored at the earlier of the two first stamps, so
  // a paced replay keeps the recorded interleaving of LiDAR and IMU.
  auto pace = std::make_shared<PaceClock>();
  pace->pace = options.pace;
  pace->data_start_ns = data_start_ns(options, ports);

  TrajectoryWriter trajectory(options.trajectory_tum);
  std::unique_ptr<TrajectoryWriter> imu_rate;
  if (!options.imu_rate_tum.empty()) imu_rate = std::make_unique<TrajectoryWriter>(options.imu_rate_tum);
  std::unique_ptr<TrajectoryWriter> map_frame;
  if (!options.map_frame_tum.empty()) map_frame = std::make_unique<TrajectoryWriter>(options.map_frame_tum);
  ScanLog scan_log(options.scan_log_csv);

  PipelineOptions po;
  po.ordering = options.pace > 0.0 ? Ordering::Arrival : Ordering::Lockstep;
  po.imu_rate_poses = imu_rate != nullptr || (!options.pose_socket.empty() && config.pose_socket.imu_rate);
  po.pose_socket = options.pose_socket;
  po.realtime_threads = options.pace > 0.0;  // a bench replay as fast as possible needs no RT priorities
  const int viewer_port = options.foxglove_port > 0 ? options.foxglove_port : config.viewer.foxglove_port;
  if (viewer_port > 0) po.viewer = std::make_shared<FoxgloveServer>(config.viewer, config.extrinsics, static_cast<std::uint16_t>(viewer_port));
  Pipeline pipeline(config, po);
  // With the backend, the scan poses are kept and written corrected once the drive is over
  // (every loop known): the same file on every run, whatever the threads' timing.
  std::vector<NavState> scan_poses;
  // Sinks run on the publisher thread, in pose order.
  pipeline.add_sink([&](const PoseEvent& ev) {
    const auto& m = ev.message;
    if (m.type == pose::MessageType::ImuPose) {
      if (imu_rate) imu_rate->write(m.time, m.position, m.orientation);
      return;
    }
    if (map_frame && (m.flags & pose::kNotLocalized) == 0) map_frame->write(m.time, m.map_position, m.map_orientation);
    if (pipeline.backend() != nullptr) {
      NavState s;
      s.time = m.time;
      s.position = m.position;
      s.rotation = m.orientation.toRotationMatrix();
      scan_poses.push_back(s);
    } else {
      trajectory.write(m.time, m.position, m.orientation);
    }
    scan_log.write(m.time, ev.diagnostics);
  });
  LidarInput input = lidar_input(pipeline, options, ports, pace);
  pace->host_start_steady_ns = steady_ns();
  pipeline.start(std::move(input.source), imu_input(options, pace));

  ProgressBar progress(options.progress, input.total);
  while (!pipeline.finished() && pipeline.error().empty()) {
    progress.update(input.done(), pipeline.lidar_output().sweeps());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  pipeline.join();
  progress.update(input.total, pipeline.lidar_output().sweeps());
  progress.finish();
  if (!pipeline.error().empty()) throw std::runtime_error(pipeline.error());

  input.warn();
  print_summary(pipeline, input, std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(), out);
  if (BackendWorker* backend = pipeline.backend()) {
    for (const auto& s : backend->backend().corrected_trajectory(scan_poses)) trajectory.write(s);
    out << backend->summary();
  }
  const bool complete = close_outputs(trajectory, imu_rate.get(), map_frame.get(), scan_log, out);
  out << "trajectory: " << options.trajectory_tum << (complete ? "" : " (incomplete)") << '\n';
  if (pipeline.totals().processed == 0) {
    spdlog::error("no pose was estimated: check that the IMU and the LiDAR input cover the same time span");
    return 1;
  }
  return complete ? 0 : 1;
}

}  // namespace liod
