// The pose socket's clients in C (clients/c/liod_pose.h, through example_print_poses.c) and Python
// (clients/python/liod_pose.py, through its two examples) read a live pipeline: the simulated
// drive replayed with its poses served on a Unix socket. Each example runs as a child process and
// prints the poses it decoded; they must be the first poses the pipeline published, in order, with
// the same times, positions, orientations and flags to the last bit.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"
#include "test_support.hpp"
#include "gated_source.hpp"

using namespace liod;
using liod::test::GatedSource;

namespace {

constexpr long kPoses = 200;  // scan-rate and IMU-rate poses: a second of the drive and more


/// A program found on PATH, or a path that does not exist naming what is missing.
std::filesystem::path on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path != nullptr ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const auto candidate = std::filesystem::path(dir) / name;
    if (!dir.empty() && ::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return std::filesystem::path("/nonexistent/PATH") / name;
}

/// A child process with its standard output and error in files.
struct Child {
  pid_t pid = -1;
  std::filesystem::path out, err;
};

Child spawn(const std::vector<std::string>& argv, const std::filesystem::path& out, const std::filesystem::path& err) {
  Child c{-1, out, err};
  c.pid = ::fork();
  if (c.pid == 0) {
    std::freopen(out.c_str(), "w", stdout);
    std::freopen(err.c_str(), "w", stderr);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return c;
}

/// Waits (bounded) for the child; its exit status, or -1 when it had to be killed.
int reap(const Child& c) {
  int status = 0;
  if (!test::wait_for([&] { return ::waitpid(c.pid, &status, WNOHANG) == c.pid; }, std::chrono::milliseconds(60000))) {
    ::kill(c.pid, SIGKILL);
    ::waitpid(c.pid, &status, 0);
    return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Replays the simulated drive with its poses on a socket; `clients(socket)` starts the client
/// processes, which must all connect before the first sweep. Returns the published poses in order.
std::vector<pose::PoseMessage> serve_drive(const std::filesystem::path& drive, const test::ScratchDir& dir,
                                           const std::function<std::vector<Child>(const std::string&)>& clients,
                                           std::vector<Child>& started) {
  Config config = test::drive_config(drive);
  config.pose_socket.client_buffer_bytes = 8 << 20;  // a slow client (Python) skips nothing
  config.pose_socket.health_interval_s = 0.05;       // health messages among the poses, and before them
  PipelineOptions po;
  po.ordering = Ordering::Lockstep;
  po.pose_socket = (dir / "pose.sock").string();
  po.realtime_threads = false;
  std::mutex mutex;
  std::vector<pose::PoseMessage> published;
  Pipeline pipeline(config, po);
  pipeline.add_sink([&](const PoseEvent& ev) {
    const std::lock_guard<std::mutex> lock(mutex);
    published.push_back(ev.message);
  });
  auto pace = std::make_shared<PaceClock>();
  std::atomic<bool> go{false};
  const std::vector<std::uint16_t> ports{6699, 7788};
  pipeline.start(std::make_unique<GatedSource>(std::make_unique<PcapLidarSource>((drive / "lidar.pcap").string(), ports, pace), go),
                 std::make_unique<CsvImuSource>((drive / "imu.csv").string(), pace));
  started = clients(po.pose_socket);
  const std::string connected = "\"clients\":" + std::to_string(started.size()) + ",";
  HealthRates rates;
  const bool all_connected = test::wait_for([&] { return pipeline.health_json(rates).find(connected) != std::string::npos; },
                                            std::chrono::milliseconds(20000));
  // Health messages reach the connected clients before the first pose (a few intervals).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  go = true;
  EXPECT_TRUE(all_connected) << "the clients did not connect: " << pipeline.health_json(rates);
  EXPECT_TRUE(test::wait_for([&] { return pipeline.finished(); }, std::chrono::milliseconds(300000)));
  pipeline.join();
  EXPECT_EQ(pipeline.error(), "");
  return published;
}

std::vector<std::vector<std::string>> fields(const std::filesystem::path& file, char sep) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::istringstream s(line);
    for (std::string x; std::getline(s, x, sep);) {
      if (!x.empty() || sep != ' ') f.push_back(x);
    }
    rows.push_back(f);
  }
  return rows;
}

double number(const std::string& s) { return std::strtod(s.c_str(), nullptr); }

/// The printed lines "scan|imu SEQ TIME X Y Z QX QY QZ QW FLAGS STATUS MAP_SEQ MAP_X MAP_Y MAP_Z"
/// (the examples' format)
/// are the first published poses, exactly; the sequence numbers increase (health messages
/// between poses take numbers too).
void expect_printed_poses(const std::vector<std::vector<std::string>>& rows, const std::vector<pose::PoseMessage>& published,
                          const std::string& who) {
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kPoses)) << who;
  ASSERT_GE(published.size(), rows.size()) << who;
  std::size_t scans = 0;
  long last_sequence = -1;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& f = rows[i];
    const auto& m = published[i];
    ASSERT_EQ(f.size(), 16U) << who << " line " << i;
    EXPECT_EQ(f[0], m.type == pose::MessageType::ScanPose ? "scan" : "imu") << who << " line " << i;
    scans += f[0] == "scan" ? 1 : 0;
    EXPECT_GT(std::stol(f[1]), last_sequence) << who << " line " << i;
    last_sequence = std::stol(f[1]);
    EXPECT_EQ(number(f[2]), m.time) << who << " line " << i;
    EXPECT_EQ(number(f[3]), m.position.x()) << who << " line " << i;
    EXPECT_EQ(number(f[4]), m.position.y()) << who << " line " << i;
    EXPECT_EQ(number(f[5]), m.position.z()) << who << " line " << i;
    EXPECT_EQ(number(f[6]), m.orientation.x()) << who << " line " << i;
    EXPECT_EQ(number(f[7]), m.orientation.y()) << who << " line " << i;
    EXPECT_EQ(number(f[8]), m.orientation.z()) << who << " line " << i;
    EXPECT_EQ(number(f[9]), m.orientation.w()) << who << " line " << i;
    EXPECT_EQ(std::stoul(f[10]), m.flags) << who << " line " << i;
    EXPECT_EQ(f[11], pose::flag_names(m.flags)) << who << " line " << i;
    EXPECT_EQ(std::stoul(f[12]), m.correction_sequence) << who << " line " << i;
    EXPECT_EQ(number(f[13]), m.map_position.x()) << who << " line " << i;
    EXPECT_EQ(number(f[14]), m.map_position.y()) << who << " line " << i;
    EXPECT_EQ(number(f[15]), m.map_position.z()) << who << " line " << i;
  }
  // Both message types were decoded, and the vehicle moved.
  EXPECT_GT(scans, 0U) << who;
  EXPECT_LT(scans, rows.size()) << who;
  EXPECT_NE(published[rows.size() - 1].position, published[0].position) << who;
}

}  // namespace

TEST(PoseClients, CExampleDecodesTheLivePipeline) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  LIOD_REQUIRE_PROGRAM("liod-pose-example-c");
  const test::ScratchDir dir("client-c");
  std::vector<Child> children;
  const auto published = serve_drive(*drive, dir, [&](const std::string& sock) {
    return std::vector<Child>{spawn({test::built_program("liod-pose-example-c").string(), "--socket", sock, "--count",
                                     std::to_string(kPoses)},
                                    dir / "c.out", dir / "c.err")};
  }, children);
  ASSERT_EQ(children.size(), 1U);
  EXPECT_EQ(reap(children[0]), 0) << test::slurp(dir / "c.err");
  expect_printed_poses(fields(dir / "c.out", ' '), published, "C example");
}

TEST(PoseClients, PythonExamplesDecodeTheLivePipeline) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto python = on_path("python3");
  LIOD_REQUIRE_PATH(python, "python3", "apt-get install python3");
  const test::ScratchDir dir("client-py");
  const auto examples = test::source_dir() / "clients" / "python";
  std::vector<Child> children;
  const auto published = serve_drive(*drive, dir, [&](const std::string& sock) {
    return std::vector<Child>{
        spawn({python.string(), (examples / "example_print_poses.py").string(), "--socket", sock, "--count", std::to_string(kPoses)},
              dir / "print.out", dir / "print.err"),
        spawn({python.string(), (examples / "example_log_csv.py").string(), "--socket", sock, "--count", std::to_string(kPoses),
               "--out", (dir / "poses.csv").string()},
              dir / "csv.out", dir / "csv.err")};
  }, children);
  ASSERT_EQ(children.size(), 2U);
  EXPECT_EQ(reap(children[0]), 0) << test::slurp(dir / "print.err");
  EXPECT_EQ(reap(children[1]), 0) << test::slurp(dir / "csv.err");
  expect_printed_poses(fields(dir / "print.out", ' '), published, "example_print_poses.py");

  // The CSV log: a header, then the same poses with velocity, angular rate and standard deviations.
  auto rows = fields(dir / "poses.csv", ',');
  ASSERT_FALSE(rows.empty());
  const std::vector<std::string> header = rows.front();
  ASSERT_EQ(header.size(), 24U);
  EXPECT_EQ(header[2], "time");
  rows.erase(rows.begin());
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kPoses));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto& f = rows[i];
    const auto& m = published[i];
    ASSERT_EQ(f.size(), header.size()) << "CSV row " << i;
    EXPECT_EQ(number(f[2]), m.time) << "CSV row " << i;
    EXPECT_EQ(number(f[3]), m.position.x()) << "CSV row " << i;
    EXPECT_EQ(number(f[10]), m.velocity.x()) << "CSV row " << i;
    EXPECT_EQ(number(f[15]), m.angular_rate.z()) << "CSV row " << i;
    EXPECT_EQ(number(f[16]), std::sqrt(std::max(0.0, m.covariance(0, 0)))) << "CSV row " << i;
    EXPECT_EQ(number(f[21]), std::sqrt(std::max(0.0, m.covariance(5, 5)))) << "CSV row " << i;
    EXPECT_EQ(std::stoul(f[22]), m.flags) << "CSV row " << i;
  }
  // The health reports were decoded as JSON (one summary line each on stderr).
  EXPECT_NE(test::slurp(dir / "csv.err").find("health: "), std::string::npos) << test::slurp(dir / "csv.err");
}
