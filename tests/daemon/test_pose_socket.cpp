// Pose protocol round trip, JSON mode, and the server's handling of slow and stuck clients.
#include <gtest/gtest.h>
#include <poll.h>

#include <atomic>
#include <string>
#include <thread>
#include <utility>

#include "liod/daemon/pose_client.hpp"
#include "liod/daemon/pose_protocol.hpp"
#include "liod/daemon/pose_server.hpp"
#include "test_support.hpp"
#include "pump_server.hpp"

using namespace liod;
using liod::test::pump;

namespace {
pose::PoseMessage sample_message(std::uint32_t i) {
  pose::PoseMessage m;
  m.type = i % 2 == 0 ? pose::MessageType::ScanPose : pose::MessageType::ImuPose;
  m.time = 1767225600.0 + 0.005 * i;
  m.position = Eigen::Vector3d(1.5 + i, -2.25, 0.125);
  m.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  m.velocity = Eigen::Vector3d(10.0, 0.5, -0.01);
  m.angular_rate = Eigen::Vector3d(0.01, -0.02, 0.3);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) m.covariance(r, c) = r == c ? 0.01 * (r + 1) : 0.001 * (r + c);
  m.flags = pose::kOk | pose::kKeyframe;
  m.correction_sequence = 3 + i;
  m.map_position = Eigen::Vector3d(101.5 + i, -7.75, 0.5);
  m.map_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.31, Eigen::Vector3d::UnitZ()));
  return m;
}

}  // namespace

TEST(PoseProtocol, BinaryRoundTripIsExactAndLittleEndian) {
  const auto m = sample_message(4);
  std::vector<std::uint8_t> bytes;
  pose::encode(m, bytes);
  ASSERT_EQ(bytes.size(), pose::kPoseMessageSize);
  EXPECT_EQ(bytes[0], 'L');
  EXPECT_EQ(bytes[3], 'D');
  EXPECT_EQ(bytes[4], 2);  // version 2, little-endian
  EXPECT_EQ(bytes[5], 0);
  EXPECT_EQ(bytes[8], 360 & 0xFF);
  EXPECT_EQ(bytes[9], 360 >> 8);
  EXPECT_EQ(bytes[300], 7);  // the correction sequence, little-endian, after the flags
  EXPECT_EQ(bytes[301], 0);
  pose::Message out;
  std::size_t used = 0;
  ASSERT_EQ(pose::decode(bytes, out, used), pose::DecodeStatus::Ok);
  EXPECT_EQ(used, bytes.size());
  EXPECT_EQ(out.pose.time, m.time);
  EXPECT_EQ(out.pose.position, m.position);
  EXPECT_EQ(out.pose.orientation.coeffs(), m.orientation.coeffs());
  EXPECT_EQ(out.pose.covariance, m.covariance);
  EXPECT_EQ(out.pose.flags, m.flags);
  EXPECT_EQ(out.pose.correction_sequence, m.correction_sequence);
  EXPECT_EQ(out.pose.map_position, m.map_position);
  EXPECT_EQ(out.pose.map_orientation.coeffs(), m.map_orientation.coeffs());
  // A version 1 stream is not read as this one.
  std::vector<std::uint8_t> v1 = bytes;
  v1[4] = 1;
  EXPECT_EQ(pose::decode(v1, out, used), pose::DecodeStatus::Invalid);
  // Partial input waits for more; a wrong magic is rejected.
  EXPECT_EQ(pose::decode(std::span(bytes).first(100), out, used), pose::DecodeStatus::NeedMore);
  bytes[0] = 'X';
  EXPECT_EQ(pose::decode(bytes, out, used), pose::DecodeStatus::Invalid);
}

TEST(PoseProtocol, CovarianceReordersFilterBlocks) {
  Eigen::Matrix<double, 15, 15> s = Eigen::Matrix<double, 15, 15>::Zero();
  s.diagonal().segment<3>(0).setConstant(2.0);  // rotation
  s.diagonal().segment<3>(3).setConstant(5.0);  // position
  s(0, 3) = s(3, 0) = 0.7;
  const auto c = pose::pose_covariance_from_state(s);
  EXPECT_EQ(c(0, 0), 5.0);
  EXPECT_EQ(c(3, 3), 2.0);
  EXPECT_EQ(c(0, 3), 0.7);
}

TEST(PoseProtocol, RequestLinesInAnyChunking) {
  const std::string bytes = "junk\njson\r\nscan  \nbinary\nscan\n";
  for (std::size_t piece : {std::size_t{1}, std::size_t{3}, bytes.size()}) {
    pose::ClientMode mode;
    pose::RequestReader reader;
    for (std::size_t i = 0; i < bytes.size(); i += piece) reader.feed(std::string_view(bytes).substr(i, piece), mode);
    EXPECT_FALSE(mode.json) << "pieces of " << piece;
    EXPECT_TRUE(mode.scan_only) << "pieces of " << piece;
  }
}

// Found by fuzz_pose_socket: a line over the length limit was dropped when a piece ended past the
// limit, and the rest of it then read as a line of its own: "<garbage>json" switched the client to
// JSON or not depending on where recv() happened to cut the bytes.
TEST(PoseProtocol, RequestAtTheEndOfAnOverlongLineIsIgnored) {
  const std::pair<std::size_t, std::size_t> garbage_and_piece[] = {{1025, 1}, {1280, 256}, {1280, 1285}};
  for (const auto& [garbage, piece] : garbage_and_piece) {
    const std::string overlong = std::string(garbage, 'x') + "json\n";
    pose::ClientMode mode;
    pose::RequestReader reader;
    for (std::size_t i = 0; i < overlong.size(); i += piece) reader.feed(std::string_view(overlong).substr(i, piece), mode);
    EXPECT_FALSE(mode.json) << "pieces of " << piece;
    reader.feed("json\n", mode);  // the next line is read normally
    EXPECT_TRUE(mode.json) << "pieces of " << piece;
  }
  // The longest line still read as a request: kMaxLine bytes with trailing spaces.
  pose::ClientMode mode;
  pose::RequestReader reader;
  reader.feed("json" + std::string(pose::RequestReader::kMaxLine - 4, ' ') + "\n", mode);
  EXPECT_TRUE(mode.json);
}

TEST(PoseSocket, ServesBinaryAndJsonClients) {
  const test::ScratchDir dir("pose");
  const std::string path = (dir / "pose.sock").string();
  PoseSocketConfig cfg;
  PoseServer server(path, cfg);
  EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::all,
            std::filesystem::perms::owner_read | std::filesystem::perms::owner_write | std::filesystem::perms::group_read |
                std::filesystem::perms::group_write);
  PoseClient binary(path);
  PoseClient json(path);
  json.request("json");
  PoseClient scan_only(path);
  scan_only.request("scan");
  pump(server, 100);
  ASSERT_EQ(server.stats().clients, 3U);
  for (std::uint32_t i = 0; i < 4; ++i) server.broadcast(sample_message(i));
  pump(server, 50);
  pose::Message m;
  for (std::uint32_t i = 0; i < 4; ++i) {
    ASSERT_TRUE(binary.read(m, std::chrono::milliseconds(1000)));
    EXPECT_EQ(m.pose.time, sample_message(i).time);
  }
  std::string line;
  ASSERT_TRUE(json.read_line(line, std::chrono::milliseconds(1000)));
  EXPECT_EQ(line.rfind("{\"type\":\"scan\"", 0), 0U) << line;
  EXPECT_NE(line.find("\"status\":\"ok|keyframe\""), std::string::npos) << line;
  ASSERT_TRUE(scan_only.read(m, std::chrono::milliseconds(1000)));
  EXPECT_EQ(m.type, pose::MessageType::ScanPose);
  ASSERT_TRUE(scan_only.read(m, std::chrono::milliseconds(1000)));
  EXPECT_EQ(m.type, pose::MessageType::ScanPose);
  EXPECT_EQ(m.pose.time, sample_message(2).time);
  server.broadcast_health("{\"x\":1}");
  pump(server, 20);
  ASSERT_TRUE(binary.read(m, std::chrono::milliseconds(1000)));
  EXPECT_EQ(m.type, pose::MessageType::Health);
  EXPECT_EQ(m.health, "{\"x\":1}");
}

// A client that never reads: broadcasting never blocks, the reading client gets every message,
// the stuck one skips messages and is disconnected after stuck_timeout_s.
TEST(PoseSocket, StuckClientIsSkippedThenDroppedOthersServed) {
  const test::ScratchDir dir("stuck");
  const std::string path = (dir / "pose.sock").string();
  PoseSocketConfig cfg;
  cfg.client_buffer_bytes = 64 * 1024;
  cfg.stuck_timeout_s = 0.5;
  PoseServer server(path, cfg);
  PoseClient stuck(path);  // never reads
  std::atomic<std::uint32_t> received{0};
  std::atomic<bool> reader_ok{true};
  constexpr std::uint32_t kMessages = 20000;  // ~6 MB: far more than the socket buffers hold
  std::thread reader([&] {
    PoseClient good(path);
    pose::Message m;
    std::uint32_t expected_seq_time = 0;
    while (received < kMessages && good.read(m, std::chrono::milliseconds(3000))) {
      if (m.type == pose::MessageType::Health) continue;
      if (m.pose.time != sample_message(expected_seq_time).time) reader_ok = false;
      ++expected_seq_time;
      ++received;
    }
  });
  ASSERT_TRUE(test::wait_for([&] {
    pump(server, 5);
    return server.stats().clients == 2U;
  }, std::chrono::milliseconds(5000)));
  double worst_us = 0;
  std::vector<pollfd> fds;
  for (std::uint32_t i = 0; i < kMessages; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    server.broadcast(sample_message(i));
    worst_us = std::max(worst_us, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    if (i % 50 == 0) {  // the publisher's poll loop between bursts
      fds.clear();
      server.fill_pollfds(fds);
      ::poll(fds.data(), fds.size(), 1);
      server.handle(fds, 0);
    }
  }
  // The good client drains at its pace; keep pumping until it has everything (bounded).
  test::wait_for([&] {
    pump(server, 10);
    return received.load() >= kMessages;
  }, std::chrono::milliseconds(20000));
  reader.join();
  EXPECT_EQ(received.load(), kMessages);
  EXPECT_TRUE(reader_ok.load());
  EXPECT_GT(server.stats().skipped_messages, 0U);  // the stuck client's buffer filled
  EXPECT_LT(worst_us, 20000.0) << "a broadcast blocked";
  pump(server, 700);  // past stuck_timeout_s
  EXPECT_EQ(server.stats().dropped_stuck, 1U);
  EXPECT_EQ(server.stats().clients, 0U);  // the stuck one dropped; the reader left when done
}

TEST(PoseSocket, ReplacesStaleSocketFileAndCleansUp) {
  const test::ScratchDir dir("stale");
  const std::string path = (dir / "pose.sock").string();
  { PoseServer first(path, PoseSocketConfig{}); }
  EXPECT_FALSE(std::filesystem::exists(path));
  {
    PoseServer a(path, PoseSocketConfig{});
    // a crashed run would leave the file: a new server must still start
  }
  PoseServer b(path, PoseSocketConfig{});
  EXPECT_TRUE(std::filesystem::exists(path));
  EXPECT_THROW(PoseServer(path + std::string(200, 'x'), PoseSocketConfig{}), std::runtime_error);
}
