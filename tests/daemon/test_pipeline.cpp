// The pipeline on the simulated drive: replay is deterministic; a stuck pose client changes
// nothing; `liod run` fed over loopback UDP + an IMU source publishes the poses `liod replay`
// computes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <thread>

#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_client.hpp"
#include "liod/daemon/replay.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/daemon/trajectory_writer.hpp"
#include "sim_drive.hpp"
#include "udp_sender.hpp"

using namespace liod;

namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Config drive_config(const std::filesystem::path& drive) {
  return load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml", (drive / "extrinsics.yaml").string()});
}

struct TumPose {
  double t, x, y, z, qx, qy, qz, qw;
};
std::vector<TumPose> read_tum(const std::filesystem::path& p) {
  std::vector<TumPose> out;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    TumPose q{};
    s >> q.t >> q.x >> q.y >> q.z >> q.qx >> q.qy >> q.qz >> q.qw;
    out.push_back(q);
  }
  return out;
}

/// The reference: a replay as fast as possible (computed once).
const std::filesystem::path& reference_replay(const std::filesystem::path& drive) {
  static std::filesystem::path dir;
  if (dir.empty()) {
    dir = test::temp_dir("reference");
    ReplayOptions o;
    o.pcap = (drive / "lidar.pcap").string();
    o.imu_csv = (drive / "imu.csv").string();
    o.trajectory_tum = (dir / "scan.tum").string();
    o.imu_rate_tum = (dir / "imu.tum").string();
    std::ostringstream out;
    if (run_replay(drive_config(drive), o, out) != 0) ADD_FAILURE() << out.str();
  }
  return dir;
}

/// A LiDAR source that waits for a go signal (bounded), so clients can connect first.
class GatedSource : public LidarSource {
 public:
  GatedSource(std::unique_ptr<LidarSource> inner, const std::atomic<bool>& go) : inner_(std::move(inner)), go_(go) {}
  void run(LidarOutput& out, const std::atomic<bool>& stop) override {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!go_.load() && !stop.load() && std::chrono::steady_clock::now() < deadline) {
      out.heartbeat();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    inner_->run(out, stop);
  }
  std::string describe() const override { return "gated " + inner_->describe(); }

 private:
  std::unique_ptr<LidarSource> inner_;
  const std::atomic<bool>& go_;
};

}  // namespace

TEST(Pipeline, ReplayIsDeterministic) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto& ref = reference_replay(*drive);
  const auto dir = test::temp_dir("again");
  ReplayOptions o;
  o.pcap = (*drive / "lidar.pcap").string();
  o.imu_csv = (*drive / "imu.csv").string();
  o.trajectory_tum = (dir / "scan.tum").string();
  o.imu_rate_tum = (dir / "imu.tum").string();
  std::ostringstream out;
  ASSERT_EQ(run_replay(drive_config(*drive), o, out), 0) << out.str();
  EXPECT_NE(out.str().find("replay: "), std::string::npos);
  EXPECT_NE(out.str().find("trajectory: "), std::string::npos);
  const auto a = slurp(ref / "scan.tum");
  EXPECT_GT(read_tum(ref / "scan.tum").size(), 50U);
  EXPECT_EQ(a, slurp(dir / "scan.tum"));
  EXPECT_EQ(slurp(ref / "imu.tum"), slurp(dir / "imu.tum"));
}

// A client that connects and never reads, next to one that reads: the poses computed are those
// of the undisturbed replay, and the reading client receives every scan pose.
TEST(Pipeline, StuckClientDoesNotAffectOdometry) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto& ref = reference_replay(*drive);
  const auto dir = test::temp_dir("stuckpipe");
  Config config = drive_config(*drive);
  config.pose_socket.client_buffer_bytes = 16384;
  config.pose_socket.stuck_timeout_s = 1.0;
  PipelineOptions po;
  po.ordering = Ordering::Lockstep;
  po.pose_socket = (dir / "pose.sock").string();
  po.realtime_threads = false;
  Pipeline pipeline(config, po);
  TrajectoryWriter tum((dir / "scan.tum").string());
  pipeline.add_sink([&](const PoseEvent& ev) {
    if (ev.message.type == pose::MessageType::ScanPose) tum.write(ev.message.time, ev.message.position, ev.message.orientation);
  });
  auto pace = std::make_shared<PaceClock>();
  std::atomic<bool> go{false};
  const std::vector<std::uint16_t> ports{6699, 7788};
  pipeline.start(std::make_unique<GatedSource>(std::make_unique<PcapLidarSource>((*drive / "lidar.pcap").string(), ports, pace), go),
                 std::make_unique<CsvImuSource>((*drive / "imu.csv").string(), pace));
  PoseClient stuck(po.pose_socket);
  std::atomic<int> scan_poses{0};
  std::atomic<bool> reader_ready{false};
  std::thread reader([&] {
    PoseClient good(po.pose_socket);
    reader_ready = true;
    pose::Message m;
    while (good.read(m, std::chrono::milliseconds(5000))) {
      if (m.type == pose::MessageType::ScanPose) ++scan_poses;
    }
  });
  HealthRates rates;
  ASSERT_TRUE(test::wait_for([&] { return reader_ready && pipeline.health_json(rates).find("\"clients\":2") != std::string::npos; },
                             std::chrono::milliseconds(10000)));
  go = true;
  ASSERT_TRUE(test::wait_for([&] { return pipeline.finished(); }, std::chrono::milliseconds(300000)));
  pipeline.join();
  tum.flush();
  reader.join();  // ends on the server closing the socket (pipeline gone) or its 5 s timeout
  EXPECT_EQ(slurp(ref / "scan.tum"), slurp(dir / "scan.tum"));
  EXPECT_EQ(static_cast<std::size_t>(scan_poses.load()), read_tum(ref / "scan.tum").size());
}

namespace {

// `liod run` as a child process: LiDAR over loopback UDP, IMU from the log (transport `file`)
// at the same pace; scan poses read from its socket and compared with the replay's.
void live_matches_replay(double pace) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto liod_bin = test::binary_dir() / "bin" / "liod";
  if (!std::filesystem::exists(liod_bin)) GTEST_SKIP() << "liod binary not built";
  const auto ref = read_tum(reference_replay(*drive) / "scan.tum");
  ASSERT_FALSE(ref.empty());
  const auto dir = test::temp_dir("live" + std::to_string(static_cast<int>(pace)));
  const int port = 30000 + static_cast<int>(::getpid() % 5000) * 4 + (pace > 1 ? 2 : 0);
  const auto msop = static_cast<std::uint16_t>(port);
  const auto difop = static_cast<std::uint16_t>(port + 1);
  const std::string sock = (dir / "pose.sock").string();
  {
    std::ofstream cfg(dir / "test.yaml");
    cfg << "lidar: {msop_port: " << msop << ", difop_port: " << difop << "}\n"
        << "drivers:\n  lidar: {bind_address: 127.0.0.1}\n  imu: {transport: file, file: \"" << (*drive / "imu.csv").string()
        << "\", file_pace: " << pace << "}\n"
        << "time: {lidar_clock: sensor, imu_wait_s: 2.0}\n"
        << "threads: {lidar: {priority: 0}, imu: {priority: 0}, odometry: {priority: 0}, publisher: {priority: 0}, scan_ring: 256}\n"
        << "output: {pose_socket: \"" << sock << "\"}\n"
        << "pose_socket: {health_interval_s: 0.2, client_buffer_bytes: 8388608}\n";
  }
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string log = (dir / "liod.log").string();
    std::freopen(log.c_str(), "w", stderr);
    const std::string c1 = std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml";
    const std::string c2 = (*drive / "extrinsics.yaml").string();
    const std::string c3 = (dir / "test.yaml").string();
    ::execl(liod_bin.c_str(), "liod", "run", "--config", c1.c_str(), "--config", c2.c_str(), "--config", c3.c_str(),
            "--max-seconds", "300", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  auto reap = [&](int* status) {
    return test::wait_for([&] { return ::waitpid(child, status, WNOHANG) == child; }, std::chrono::milliseconds(15000));
  };
  ASSERT_TRUE(test::wait_for([&] { return std::filesystem::exists(sock); }, std::chrono::milliseconds(15000)))
      << slurp(dir / "liod.log");
  std::unique_ptr<PoseClient> client;
  ASSERT_TRUE(test::wait_for([&] {
    try {
      client = std::make_unique<PoseClient>(sock);
      return true;
    } catch (const std::exception&) {
      return false;
    }
  }, std::chrono::milliseconds(5000)));
  pose::Message m;
  bool health = false;
  for (int i = 0; i < 100 && !health; ++i) health = client->read(m, std::chrono::milliseconds(100)) && m.type == pose::MessageType::Health;
  ASSERT_TRUE(health) << "no health message from liod run";
  std::vector<pose::PoseMessage> scans;
  std::string last_health;
  std::thread sender([&] {
    test::send_pcap_loopback((*drive / "lidar.pcap").string(), {{6699, msop}, {7788, difop}}, pace);
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(static_cast<int>(8.0 / pace) + 120);
  while (scans.size() < ref.size() && std::chrono::steady_clock::now() < deadline) {
    if (!client->read(m, std::chrono::milliseconds(500))) continue;
    if (m.type == pose::MessageType::ScanPose) scans.push_back(m.pose);
    if (m.type == pose::MessageType::Health) last_health = m.health;
  }
  sender.join();
  // One more health report after the last packet: counters settled.
  for (int i = 0; i < 20; ++i) {
    if (client->read(m, std::chrono::milliseconds(200)) && m.type == pose::MessageType::Health) last_health = m.health;
  }
  ::kill(child, SIGTERM);
  int status = 0;
  ASSERT_TRUE(reap(&status)) << "liod run did not stop on SIGTERM";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir / "liod.log");
  ASSERT_EQ(scans.size(), ref.size()) << slurp(dir / "liod.log");
  // The paths share the decoder (which holds MSOP packets that race ahead of the first DIFOP on
  // the other socket) and a content-ordered odometry: the same scans from the first one, and the
  // same poses to the precision of the reference file.
  double worst_m = 0.0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const auto& a = ref[i];
    const auto& b = scans[i];
    ASSERT_NEAR(a.t, b.time, 1e-6) << "scan " << i;
    EXPECT_NEAR(a.x, b.position.x(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.y, b.position.y(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.z, b.position.z(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.qx, b.orientation.x(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.qy, b.orientation.y(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.qz, b.orientation.z(), 1e-5) << "scan " << i;
    EXPECT_NEAR(a.qw, b.orientation.w(), 1e-5) << "scan " << i;
    worst_m = std::max(worst_m, (Eigen::Vector3d(a.x, a.y, a.z) - b.position).norm());
  }
  std::printf("live vs replay at %gx pace: %zu scans, largest position difference %.2e m\n", pace, ref.size(), worst_m);
  EXPECT_NE(last_health.find("\"lost_packets\":0,"), std::string::npos) << last_health;
  EXPECT_NE(last_health.find("\"scan\":{\"fill\":0,\"capacity\":256,\"drops\":0}"), std::string::npos) << last_health;
}

}  // namespace

TEST(LiveVsReplay, RecordedPace) { live_matches_replay(1.0); }
TEST(LiveVsReplay, FiveTimesPace) { live_matches_replay(5.0); }
