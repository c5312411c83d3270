// `liod pose` (run_pose_client) against a pose server in this process: each --format prints the
// messages the server sent, the default output is unchanged, and tum takes scan-rate poses only.
#include <gtest/gtest.h>
#include <poll.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "liod/daemon/pose_protocol.hpp"
#include "liod/daemon/pose_server.hpp"
#include "liod/daemon/run_command.hpp"
#include "test_support.hpp"
#include "pump_server.hpp"

using namespace liod;
using liod::test::pump;

// A namespace of its own: the unity build compiles this file with other tests'.
namespace pose_command_test {

pose::PoseMessage message(std::uint32_t i) {
  pose::PoseMessage m;
  m.type = i % 2 == 0 ? pose::MessageType::ScanPose : pose::MessageType::ImuPose;
  m.time = 1767225600.0 + 0.1 * i + 1.0 / 3.0;  // 1/3: a number whose exact text needs 17 digits
  m.position = Eigen::Vector3d(1.5 + i, -2.25, 0.1);
  m.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  m.velocity = Eigen::Vector3d(10.0, 0.5, -0.01);
  m.angular_rate = Eigen::Vector3d(0.01, -0.02, 0.3);
  for (int r = 0; r < 6; ++r) m.covariance(r, r) = 0.0004 * (r + 1);
  m.flags = pose::kOk | (i % 4 == 0 ? pose::kKeyframe : 0U);
  m.correction_sequence = i / 2;
  m.map_position = m.position + Eigen::Vector3d(0.25, -0.5, 0.0);
  m.map_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.31, Eigen::Vector3d::UnitZ()));
  return m;
}


// Runs `liod pose` with `options` (socket set here) while the server sends a health message and
// messages 0..5; returns what it printed.
std::string run_pose(PoseCommandOptions options) {
  const test::ScratchDir dir("posecmd");
  const std::string path = (dir / "pose.sock").string();
  PoseServer server(path, PoseSocketConfig{});
  options.socket = path;
  options.timeout_s = 2.0;
  std::ostringstream out;
  int rc = -1;
  std::thread client([&] { rc = run_pose_client(options, out); });
  EXPECT_TRUE(test::wait_for([&] {
    pump(server, 5);
    return server.stats().clients == 1U;
  }, std::chrono::milliseconds(5000)));
  pump(server, 200);  // the client's request lines ("json", "scan") arrive before the messages
  server.broadcast_health("{\"version\":1}");
  for (std::uint32_t i = 0; i < 6; ++i) server.broadcast(message(i));
  test::wait_for([&] {
    pump(server, 10);
    return server.stats().clients == 0U;
  }, std::chrono::milliseconds(5000));
  client.join();
  EXPECT_EQ(rc, 0) << out.str();
  return out.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string f; std::getline(in, f, sep);) out.push_back(f);
  return out;
}

}  // namespace pose_command_test

using namespace pose_command_test;

TEST(PoseCommand, TextIsTheDefault) {
  PoseCommandOptions o;
  o.count = 2;
  o.health = true;
  const auto out = lines(run_pose(o));
  ASSERT_EQ(out.size(), 3U);
  EXPECT_EQ(out[0], "health {\"version\":1}");
  EXPECT_EQ(out[1],
            "scan 1767225600.333333 p 1.500 -2.250 0.100 q 0.00000 0.00000 0.14944 0.98877 v 10.000 0.500 -0.010 "
            "w 0.0100 -0.0200 0.3000 sd_xyz 0.020 0.028 0.035 ok|keyframe map 1.750 -2.750 0.100 #0");
  EXPECT_EQ(out[2].rfind("imu  1767225600.433333 p 2.500 ", 0), 0U) << out[2];
  const std::string tail = " ok map 2.750 -2.750 0.100 #0";
  EXPECT_EQ(out[2].substr(out[2].size() - tail.size()), tail) << out[2];
}

TEST(PoseCommand, JsonIsTheServersTextMode) {
  PoseCommandOptions o;
  o.format = PoseFormat::Json;
  o.count = 3;
  const auto out = lines(run_pose(o));
  ASSERT_EQ(out.size(), 3U);
  for (std::uint32_t i = 0; i < 3; ++i) {
    auto m = message(i);
    m.sequence = i + 1;  // the server's counter: the health message was 0
    EXPECT_EQ(out[i] + "\n", pose::to_json_line(m)) << i;
  }
}

TEST(PoseCommand, CsvRowsAreExact) {
  PoseCommandOptions o;
  o.format = PoseFormat::Csv;
  o.count = 4;
  const auto out = lines(run_pose(o));
  ASSERT_EQ(out.size(), 5U);
  const auto header = split(out[0], ',');
  ASSERT_EQ(header.size(), 32U);
  EXPECT_EQ(header[2], "time");
  for (std::uint32_t i = 0; i < 4; ++i) {
    const auto f = split(out[i + 1], ',');
    ASSERT_EQ(f.size(), header.size()) << out[i + 1];
    const auto m = message(i);
    EXPECT_EQ(f[0], i % 2 == 0 ? "scan" : "imu");
    EXPECT_EQ(std::stoul(f[1]), i + 1);  // the server's counter: the health message was 0
    EXPECT_EQ(std::strtod(f[2].c_str(), nullptr), m.time);
    EXPECT_EQ(std::strtod(f[3].c_str(), nullptr), m.position.x());
    EXPECT_EQ(std::strtod(f[8].c_str(), nullptr), m.orientation.z());
    EXPECT_EQ(std::strtod(f[9].c_str(), nullptr), m.orientation.w());
    EXPECT_EQ(std::strtod(f[16].c_str(), nullptr), std::sqrt(m.covariance(0, 0)));
    EXPECT_EQ(std::stoul(f[22]), m.flags);
    EXPECT_EQ(f[23], pose::flag_names(m.flags));
    EXPECT_EQ(std::stoul(f[24]), m.correction_sequence);
    EXPECT_EQ(std::strtod(f[25].c_str(), nullptr), m.map_position.x());
    EXPECT_EQ(std::strtod(f[31].c_str(), nullptr), m.map_orientation.w());
  }
}

TEST(PoseCommand, TumHasScanPosesOnly) {
  PoseCommandOptions o;
  o.format = PoseFormat::Tum;
  o.count = 3;
  o.health = true;  // a trajectory file holds poses only, whatever is asked
  const auto out = lines(run_pose(o));
  ASSERT_EQ(out.size(), 3U);
  for (std::size_t k = 0; k < 3; ++k) {
    const auto m = message(static_cast<std::uint32_t>(2 * k));  // the scan poses: 0, 2, 4
    char expected[256];
    std::snprintf(expected, sizeof expected, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f", m.time, m.position.x(),
                  m.position.y(), m.position.z(), m.orientation.x(), m.orientation.y(), m.orientation.z(), m.orientation.w());
    EXPECT_EQ(out[k], expected);
  }
}

TEST(PoseCommand, TumInTheMapFrame) {
  PoseCommandOptions o;
  o.format = PoseFormat::Tum;
  o.map_frame = true;
  o.count = 2;
  const auto out = lines(run_pose(o));
  ASSERT_EQ(out.size(), 2U);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto m = message(static_cast<std::uint32_t>(2 * k));
    char expected[256];
    std::snprintf(expected, sizeof expected, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f", m.time, m.map_position.x(),
                  m.map_position.y(), m.map_position.z(), m.map_orientation.x(), m.map_orientation.y(),
                  m.map_orientation.z(), m.map_orientation.w());
    EXPECT_EQ(out[k], expected);
  }
}
