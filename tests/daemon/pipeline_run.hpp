#pragma once
// A drive's files (LiDAR pcap + IMU CSV) through a Pipeline, every published pose collected in
// publish order with the host time it reached the sinks; and the IMU log rewritten with a fault.
#include <atomic>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"
#include "test_support.hpp"

namespace liod::test {

struct PublishedPose {
  PoseEvent event;
  std::int64_t published_steady_ns = 0;  ///< when the publisher handed it to the sinks
};

struct PipelineRun {
  std::vector<PublishedPose> poses;
  std::string health;  ///< the health JSON at the end
  std::string error;
};

/// Runs `pcap` + `imu_csv` through a pipeline. `pace` 0: lockstep (as `liod replay`); > 0: live
/// ordering at that multiple of the recorded pace. `prepare` may adjust the pipeline before start;
/// `poll` is called every 100 ms while it runs (as run_daemon's main loop would).
inline PipelineRun run_pipeline(const Config& config, const std::filesystem::path& pcap, const std::filesystem::path& imu_csv,
                                double pace, const std::function<void(PipelineOptions&)>& prepare = {},
                                const std::function<void(Pipeline&)>& poll = {}) {
  PipelineOptions po;
  po.ordering = pace > 0.0 ? Ordering::Arrival : Ordering::Lockstep;
  po.realtime_threads = false;
  if (prepare) prepare(po);
  PipelineRun run;
  Pipeline pipeline(config, po);
  pipeline.add_sink([&](const PoseEvent& ev) { run.poses.push_back({ev, steady_ns()}); });
  auto clock = std::make_shared<PaceClock>();
  clock->pace = pace;
  const std::vector<std::uint16_t> ports{static_cast<std::uint16_t>(config.lidar.msop_port),
                                         static_cast<std::uint16_t>(config.lidar.difop_port)};
  clock->data_start_ns = std::min(first_pcap_time_ns(pcap.string(), ports), first_imu_time_ns(imu_csv.string()));
  clock->host_start_steady_ns = steady_ns();
  pipeline.start(std::make_unique<PcapLidarSource>(pcap.string(), ports, clock),
                 std::make_unique<CsvImuSource>(imu_csv.string(), clock));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(10);
  while (!pipeline.finished() && pipeline.error().empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (poll) poll(pipeline);
  }
  pipeline.join();
  HealthRates rates;
  run.health = pipeline.health_json(rates);
  run.error = pipeline.error();
  return run;
}

/// Copies the IMU log, passing each data line through `edit(time, line)` (returns the new line).
inline void rewrite_imu_log(const std::filesystem::path& from, const std::filesystem::path& to,
                            const std::function<std::string(double, const std::string&)>& edit) {
  std::ifstream in(from);
  std::ofstream out(to);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || !(std::isdigit(static_cast<unsigned char>(line[0])) || line[0] == '-')) {
      out << line << '\n';
      continue;
    }
    out << edit(std::stod(line), line) << '\n';
  }
}

}  // namespace liod::test
