#include "fault_run.hpp"

#include <chrono>
#include <memory>
#include <thread>

#include "liod/config.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/fault/apply_fault.hpp"
#include "scratch_dir.hpp"

namespace liod::test {

std::vector<pose::PoseMessage> FaultRun::of_type(pose::MessageType type) const {
  std::vector<pose::PoseMessage> out;
  for (const auto& p : poses) {
    if (p.type == type) out.push_back(p);
  }
  return out;
}

FaultRun run_with_faults(const FaultDrive& drive, const std::vector<std::string>& faults) {
  FaultRun run;
  const ScratchDir scratch("run");
  {
    fault::Recording recording = drive.recording;
    for (std::size_t i = 0; i < faults.size(); ++i) {
      run.applied.push_back(fault::apply_fault(fault::parse_fault(faults[i]), recording, i + 1));
    }
    fault::write_recording(recording, scratch.path() / "lidar.pcap", scratch.path() / "imu.csv");
  }
  const std::string source_dir = LIOD_SOURCE_DIR;
  const Config config = load_config({source_dir + "/config/liod.yaml", source_dir + "/config/vehicles/liod-sim-car.yaml",
                                     (drive.dir / "extrinsics.yaml").string()});
  PipelineOptions options;
  options.ordering = Ordering::Lockstep;  // as `liod replay` without --pace: deterministic
  options.imu_rate_poses = true;
  options.realtime_threads = false;
  Pipeline pipeline(config, options);
  pipeline.add_sink([&run](const PoseEvent& ev) { run.poses.push_back(ev.message); });
  auto pace = std::make_shared<PaceClock>();
  const std::vector<std::uint16_t> ports{static_cast<std::uint16_t>(config.lidar.msop_port),
                                         static_cast<std::uint16_t>(config.lidar.difop_port)};
  pipeline.start(std::make_unique<PcapLidarSource>((scratch.path() / "lidar.pcap").string(), ports, pace),
                 std::make_unique<CsvImuSource>((scratch.path() / "imu.csv").string(), pace));
  // A 25 s drive replays in a few seconds; a pipeline that blocks for good never finishes.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  while (!pipeline.finished() && pipeline.error().empty() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  run.finished = pipeline.finished();
  if (!run.finished) pipeline.drain(std::chrono::milliseconds(2000));
  pipeline.join();
  run.error = pipeline.error();
  run.totals = pipeline.totals();
  run.lidar = pipeline.lidar_output().decoder_stats();
  run.lidar_refused = pipeline.lidar_output().transport.refused.load();
  run.imu_saturated = pipeline.imu_output().saturated();
  run.imu_out_of_range = pipeline.imu_output().out_of_range();
  return run;
}

}  // namespace liod::test
