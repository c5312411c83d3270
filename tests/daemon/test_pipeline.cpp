// The pipeline on the simulated drive: replay is deterministic; a stuck pose client changes
// nothing; `liod run` fed over loopback UDP + an IMU source publishes the poses `liod replay`
// computes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_client.hpp"
#include "liod/daemon/replay.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/daemon/trajectory_writer.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"
#include "udp_sender.hpp"
#include "gated_source.hpp"

using namespace liod;
using namespace liod::test;

namespace {


// The scan log's filter state agrees with the trajectory written beside it: its body-frame speed
// with the poses' differences, its gravity has the configured magnitude, its biases are a MEMS
// IMU's, and the hold flag is a flag.
void expect_scan_log_state_matches_trajectory(const std::filesystem::path& log, const std::vector<test::TumPose>& poses) {
  std::ifstream in(log);
  std::string header;
  std::getline(in, header);
  ASSERT_NE(header.find(",velocity_x,"), std::string::npos) << header;
  const std::string last = "gravity_z,forward_hold";
  ASSERT_EQ(header.substr(header.size() - last.size()), last) << header;
  std::map<long long, std::vector<double>> rows;  // by time in ms
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> f;
    std::istringstream fields(line);
    std::string field;
    while (std::getline(fields, field, ',')) f.push_back(std::strtod(field.c_str(), nullptr));
    ASSERT_EQ(f.size(), 30U) << line;
    rows[std::llround(f[0] * 1000.0)] = f;
  }
  ASSERT_GT(rows.size(), 50U);
  std::vector<double> speed_errors;
  for (std::size_t i = 1; i + 1 < poses.size(); ++i) {
    const auto row = rows.find(std::llround(poses[i].t * 1000.0));
    if (row == rows.end()) continue;
    const auto& f = row->second;
    const double logged = std::hypot(f[14], f[15], f[16]);
    const double dt = poses[i + 1].t - poses[i - 1].t;
    const double moved = std::hypot(poses[i + 1].x - poses[i - 1].x, poses[i + 1].y - poses[i - 1].y, poses[i + 1].z - poses[i - 1].z);
    speed_errors.push_back(std::abs(logged - moved / dt));
    EXPECT_NEAR(std::hypot(f[26], f[27], f[28]), 9.80665, 1e-3);
    for (int axis = 20; axis < 23; ++axis) EXPECT_LT(std::abs(f[axis]), 0.5);  // m/s^2
    for (int axis = 23; axis < 26; ++axis) EXPECT_LT(std::abs(f[axis]), 0.05);  // rad/s
    EXPECT_TRUE(f[29] == 0.0 || f[29] == 1.0);
  }
  ASSERT_GT(speed_errors.size(), 50U);
  std::sort(speed_errors.begin(), speed_errors.end());
  EXPECT_LT(speed_errors[speed_errors.size() / 2], 0.1) << "median |logged speed - speed from the poses| (m/s)";
}

}  // namespace

TEST(Pipeline, ReplayIsDeterministic) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto& ref = reference_replay(*drive);
  const test::ScratchDir dir("again");
  ReplayOptions o;
  o.pcap = (*drive / "lidar.pcap").string();
  o.imu_csv = (*drive / "imu.csv").string();
  o.trajectory_tum = (dir / "scan.tum").string();
  o.imu_rate_tum = (dir / "imu.tum").string();
  o.scan_log_csv = (dir / "scans.csv").string();
  std::ostringstream out;
  ASSERT_EQ(run_replay(drive_config(*drive), o, out), 0) << out.str();
  EXPECT_NE(out.str().find("replay: "), std::string::npos);
  EXPECT_NE(out.str().find("trajectory: "), std::string::npos);
  expect_scan_log_state_matches_trajectory(dir / "scans.csv", read_tum(dir / "scan.tum"));
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
  const test::ScratchDir dir("stuckpipe");
  Config config = drive_config(*drive);
  config.pose_socket.client_buffer_bytes = 16384;
  config.pose_socket.stuck_timeout_s = 1.0;
  PipelineOptions po;
  po.ordering = Ordering::Lockstep;
  po.pose_socket = (dir / "pose.sock").string();
  po.realtime_threads = false;
  TrajectoryWriter tum((dir / "scan.tum").string());  // outlives the pipeline's sink threads
  Pipeline pipeline(config, po);
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

/// `liod run` (or, with a recording directory, `liod record --out DIR`) as a child process:
/// LiDAR over loopback UDP on ports of its own, IMU from the drive's log (transport `file`) at
/// `pace`, poses on a socket in `dir`.
class LiveDaemon {
 public:
  /// `file_size_limit` > 0: the child's RLIMIT_FSIZE, with SIGXFSZ ignored (a write past it
  /// fails with EFBIG, as on a full disk).
  LiveDaemon(const std::filesystem::path& drive, const std::string& name, double pace, int port_slot,
             const std::string& record_dir = "", rlim_t file_size_limit = 0)
      : dir(name), sock((dir / "pose.sock").string()),
        msop(static_cast<std::uint16_t>(30000 + static_cast<int>(::getpid() % 2500) * 8 + port_slot * 2)),
        difop(static_cast<std::uint16_t>(msop + 1)), drive_(drive), record_dir_(record_dir),
        file_size_limit_(file_size_limit) {
    // lock_memory off: a test never pins its memory on a machine it shares (that is for `liod run`
    // on the vehicle). No skipping of scans when the odometry falls behind (scan_max_lag_s): these
    // tests compare every scan with the replay's, on a test machine that may be slower than the
    // vehicle's (Overload.* tests the skipping).
    std::ofstream cfg(config_file());
    cfg << "lidar: {msop_port: " << msop << ", difop_port: " << difop << "}\n"
        << "drivers:\n  lidar: {bind_address: 127.0.0.1}\n  imu: {transport: file, file: \"" << (drive / "imu.csv").string()
        << "\", file_pace: " << pace << "}\n"
        << "time: {lidar_clock: sensor, imu_wait_s: 2.0}\n"
        << "threads: {lidar: {priority: 0}, imu: {priority: 0}, odometry: {priority: 0}, publisher: {priority: 0}, scan_ring: 256, "
        << "lock_memory: false, scan_max_lag_s: 3600}\n"
        << "output: {pose_socket: \"" << sock << "\"}\n"
        << "pose_socket: {health_interval_s: 0.2, client_buffer_bytes: 8388608}\n";
  }
  ~LiveDaemon() {
    if (child_ > 0) {
      ::kill(child_, SIGKILL);
      ::waitpid(child_, nullptr, 0);
    }
  }
  LiveDaemon(const LiveDaemon&) = delete;
  LiveDaemon& operator=(const LiveDaemon&) = delete;

  std::filesystem::path config_file() const { return dir / "test.yaml"; }
  pid_t pid() const { return child_; }
  /// Everything `load_config` needs to see what the daemon saw.
  std::vector<std::string> config_files() const {
    return {std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml", (drive_ / "extrinsics.yaml").string(), config_file().string()};
  }
  std::string log() const { return slurp(dir / "liod.log"); }

  /// Starts it and connects `client` once it serves (a health message arrived).
  testing::AssertionResult start() {
    const auto bin = test::binary_dir() / "bin" / "liod";
    const auto files = config_files();
    child_ = ::fork();
    if (child_ < 0) return testing::AssertionFailure() << "fork failed";
    if (child_ == 0) {
      std::freopen((dir / "liod.log").c_str(), "w", stderr);
      if (file_size_limit_ > 0) {
        ::signal(SIGXFSZ, SIG_IGN);  // kept across exec
        const rlimit limit{file_size_limit_, file_size_limit_};
        ::setrlimit(RLIMIT_FSIZE, &limit);
      }
      if (record_dir_.empty()) {
        ::execl(bin.c_str(), "liod", "run", "--config", files[0].c_str(), "--config", files[1].c_str(), "--config",
                files[2].c_str(), "--max-seconds", "300", static_cast<char*>(nullptr));
      } else {
        ::execl(bin.c_str(), "liod", "record", "--config", files[0].c_str(), "--config", files[1].c_str(), "--config",
                files[2].c_str(), "--out", record_dir_.c_str(), "--max-seconds", "300", static_cast<char*>(nullptr));
      }
      ::_exit(127);
    }
    if (!test::wait_for([&] { return std::filesystem::exists(sock); }, std::chrono::milliseconds(15000))) {
      return testing::AssertionFailure() << "no pose socket\n" << log();
    }
    const bool connected = test::wait_for([&] {
      try {
        client = std::make_unique<PoseClient>(sock);
        return true;
      } catch (const std::exception&) {
        return false;
      }
    }, std::chrono::milliseconds(5000));
    if (!connected) return testing::AssertionFailure() << "cannot connect\n" << log();
    pose::Message m;
    for (int i = 0; i < 100; ++i) {
      if (client->read(m, std::chrono::milliseconds(100)) && m.type == pose::MessageType::Health) return testing::AssertionSuccess();
    }
    return testing::AssertionFailure() << "no health message\n" << log();
  }

  /// Sends the drive's pcap at `pace` while reading scan poses until `expected` arrived (or a
  /// deadline); then waits for one more health report, with the counters settled.
  std::size_t send_and_collect(double pace, std::size_t expected) {
    std::size_t sent = 0;
    std::thread sender([&] { sent = test::send_pcap_loopback((drive_ / "lidar.pcap").string(), {{6699, msop}, {7788, difop}}, pace); });
    pose::Message m;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(static_cast<int>(8.0 / pace) + 120);
    while (scans.size() < expected && std::chrono::steady_clock::now() < deadline) {
      if (!client->read(m, std::chrono::milliseconds(500))) continue;
      if (m.type == pose::MessageType::ScanPose) scans.push_back(m.pose);
      if (m.type == pose::MessageType::Health) last_health = m.health;
    }
    sender.join();
    for (int i = 0; i < 20; ++i) {
      if (client->read(m, std::chrono::milliseconds(200)) && m.type == pose::MessageType::Health) last_health = m.health;
    }
    return sent;
  }

  /// SIGTERM; succeeds when it exits with `expected_exit` within 15 s.
  testing::AssertionResult stop(int expected_exit = 0) {
    ::kill(child_, SIGTERM);
    int status = 0;
    const bool reaped = test::wait_for([&] { return ::waitpid(child_, &status, WNOHANG) == child_; }, std::chrono::milliseconds(15000));
    if (!reaped) return testing::AssertionFailure() << "did not stop on SIGTERM\n" << log();
    child_ = -1;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != expected_exit) {
      return testing::AssertionFailure() << "exit status " << status << "\n" << log();
    }
    return testing::AssertionSuccess();
  }

  const test::ScratchDir dir;
  const std::string sock;
  const std::uint16_t msop, difop;
  std::unique_ptr<PoseClient> client;
  std::vector<pose::PoseMessage> scans;
  std::string last_health;

 private:
  std::filesystem::path drive_;
  std::string record_dir_;
  rlim_t file_size_limit_ = 0;
  pid_t child_ = -1;
};

// `liod run` fed at the given pace; its scan poses compared with the replay's.
void live_matches_replay(double pace) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  LIOD_REQUIRE_PROGRAM("liod");
  const auto ref = read_tum(reference_replay(*drive) / "scan.tum");
  ASSERT_FALSE(ref.empty());
  LiveDaemon live(*drive, "live" + std::to_string(static_cast<int>(pace)), pace, pace > 1 ? 1 : 0);
  ASSERT_TRUE(live.start());
  live.send_and_collect(pace, ref.size());
  ASSERT_TRUE(live.stop());
  const auto& scans = live.scans;
  ASSERT_EQ(scans.size(), ref.size()) << live.log();
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
  EXPECT_NE(live.last_health.find("\"lost_packets\":0,"), std::string::npos) << live.last_health;
  EXPECT_NE(live.last_health.find("\"scan\":{\"fill\":0,\"capacity\":256,\"drops\":0}"), std::string::npos) << live.last_health;
}

}  // namespace

TEST(LiveVsReplay, RecordedPace) { live_matches_replay(1.0); }
TEST(LiveVsReplay, FiveTimesPace) { live_matches_replay(5.0); }

// `liod record`: what the drivers received is on disk, complete and valid, and replays to the
// poses of the source drive.
TEST(Record, RecordingReplaysToTheSourcePoses) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  LIOD_REQUIRE_PROGRAM("liod");
  const auto& ref = reference_replay(*drive);
  const std::size_t ref_scans = read_tum(ref / "scan.tum").size();
  const test::ScratchDir rec("recording");
  LiveDaemon live(*drive, "record", 5.0, 2, (rec / "drive").string());
  ASSERT_TRUE(live.start());
  const std::size_t sent = live.send_and_collect(5.0, ref_scans);
  ASSERT_TRUE(live.stop());
  ASSERT_EQ(live.scans.size(), ref_scans) << live.log();

  // Every datagram, in order per port, with its payload intact.
  std::map<std::uint16_t, std::vector<std::vector<std::uint8_t>>> source, recorded;
  auto read_pcap = [](const std::filesystem::path& path, auto& by_port, bool& clean) {
    drivers::PcapReader reader(path);
    drivers::UdpDatagram d;
    while (reader.next(d)) by_port[d.dst_port].emplace_back(d.payload.begin(), d.payload.end());
    clean = reader.error().empty() && reader.stats().dropped() == 0;
  };
  bool source_clean = false, recorded_clean = false;
  read_pcap(*drive / "lidar.pcap", source, source_clean);
  read_pcap(rec / "drive" / "lidar.pcap", recorded, recorded_clean);
  EXPECT_TRUE(recorded_clean);
  EXPECT_EQ(recorded[live.msop].size() + recorded[live.difop].size(), sent);
  EXPECT_TRUE(recorded[live.msop] == source[6699]) << recorded[live.msop].size() << " MSOP recorded of " << source[6699].size();
  EXPECT_TRUE(recorded[live.difop] == source[7788]) << recorded[live.difop].size() << " DIFOP recorded of " << source[7788].size();

  // The IMU log as the source had it (the writer's numbers round-trip exactly).
  auto read_imu = [](const std::filesystem::path& path) {
    drivers::ImuCsvReader reader(path);
    std::vector<ImuSample> out;
    ImuSample s;
    while (reader.next(s)) out.push_back(s);
    return out;
  };
  const auto imu_source = read_imu(*drive / "imu.csv");
  const auto imu_recorded = read_imu(rec / "drive" / "imu.csv");
  ASSERT_EQ(imu_recorded.size(), imu_source.size());
  for (std::size_t i = 0; i < imu_source.size(); ++i) {
    ASSERT_EQ(imu_recorded[i].time, imu_source[i].time) << "sample " << i;
    ASSERT_EQ(imu_recorded[i].gyro, imu_source[i].gyro) << "sample " << i;
    ASSERT_EQ(imu_recorded[i].accel, imu_source[i].accel) << "sample " << i;
  }

  // Replayed with the configuration it was recorded with: the source's poses, to the bit.
  ReplayOptions o;
  o.pcap = (rec / "drive" / "lidar.pcap").string();
  o.imu_csv = (rec / "drive" / "imu.csv").string();
  o.trajectory_tum = (rec / "scan.tum").string();
  std::ostringstream out;
  ASSERT_EQ(run_replay(load_config(live.config_files()), o, out), 0) << out.str();
  EXPECT_EQ(slurp(rec / "scan.tum"), slurp(ref / "scan.tum"));
}

// The disk fills while `liod record` runs (RLIMIT_FSIZE: writes past 256 kB fail with EFBIG):
// the recording stops there, counted and logged; the daemon publishes every pose as before and
// exits non-zero, because a file it was asked for is incomplete.
TEST(Record, AFullDiskStopsOnlyTheRecording) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  LIOD_REQUIRE_PROGRAM("liod");
  const std::size_t ref_scans = read_tum(reference_replay(*drive) / "scan.tum").size();
  const test::ScratchDir rec("recording-full");
  constexpr rlim_t kLimit = 256 * 1024;
  LiveDaemon live(*drive, "record-full", 5.0, 3, (rec / "drive").string(), kLimit);
  ASSERT_TRUE(live.start());
  live.send_and_collect(5.0, ref_scans);
  const bool alive = ::kill(live.pid(), 0) == 0;
  ASSERT_TRUE(live.stop(1));
  EXPECT_TRUE(alive);
  EXPECT_EQ(live.scans.size(), ref_scans) << live.log();
  const std::string log = live.log();
  EXPECT_NE(log.find("File too large"), std::string::npos) << log;
  // What was written before the limit is a readable capture.
  EXPECT_LE(std::filesystem::file_size(rec / "drive" / "lidar.pcap"), kLimit);
  drivers::PcapReader reader(rec / "drive" / "lidar.pcap");
  drivers::UdpDatagram d;
  std::size_t packets = 0;
  while (reader.next(d)) ++packets;
  EXPECT_GT(packets, 100U);
}
