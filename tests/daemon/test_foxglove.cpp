// The live view (foxglove_server.hpp): Foxglove WebSocket clients on 127.0.0.1 against replays
// of the simulated drive. What Foxglove Studio would show must arrive and match the replay; bad
// clients (stuck, garbage, gone mid-frame, wrong protocol) must not change a single pose.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "foxglove_client.hpp"
#include "liod/daemon/foxglove_server.hpp"
#include "pipeline_run.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"
#include "websocket_client.hpp"

namespace liod {
namespace {

using test::FoxgloveClient;

std::shared_ptr<FoxgloveServer> make_server(const Config& config) {
  return std::make_shared<FoxgloveServer>(config.viewer, config.extrinsics, 0);
}

test::PipelineRun replay_with(const Config& config, const std::filesystem::path& drive, std::shared_ptr<FoxgloveServer> server) {
  return test::run_pipeline(config, drive / "lidar.pcap", drive / "imu.csv", 0.0,
                            [&](PipelineOptions& po) { po.viewer = std::move(server); });
}

std::map<double, Eigen::Vector3d> scan_positions(const test::PipelineRun& run) {
  std::map<double, Eigen::Vector3d> out;
  for (const auto& p : run.poses) {
    if (p.event.message.type == pose::MessageType::ScanPose) out[p.event.message.time] = p.event.message.position;
  }
  return out;
}

Eigen::Vector3d position_of(const nlohmann::json& pose) {
  const auto& p = pose.at("position");
  return {p.at("x").get<double>(), p.at("y").get<double>(), p.at("z").get<double>()};
}

// The 0.5 m voxel (viewer.map_voxel_m) a point's coordinate k falls in.
long voxel_cell(const std::array<float, 3>& p, std::size_t k) { return std::lround(std::floor(static_cast<double>(p[k]) / 0.5)); }

double stamp_s(const nlohmann::json& m) { return m.at("sec").get<double>() + m.at("nsec").get<double>() * 1e-9; }

// The replay's scan position at each message's timestamp (the message must have one), after
// checking that the log times increase along the messages.
std::vector<Eigen::Vector3d> replay_positions(const std::vector<test::FoxgloveMessage>& messages,
                                              const std::map<double, Eigen::Vector3d>& truth) {
  std::vector<Eigen::Vector3d> out;
  std::uint64_t previous = 0;
  for (const auto& m : messages) {
    EXPECT_GT(m.log_time_ns, previous);
    previous = m.log_time_ns;
    const double t = stamp_s(m.body.at("timestamp"));
    const auto it = truth.lower_bound(t - 1e-6);
    if (it == truth.end() || std::abs(it->first - t) > 1e-6) {
      ADD_FAILURE() << "no scan pose at t=" << t;
      return out;
    }
    out.push_back(it->second);
  }
  return out;
}

TEST(Foxglove, ReplayReachesSubscribedViewers) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  Config config = test::drive_config(*drive);
  // Every pose must arrive: the queue holds the whole replay. With the default 8 MiB (a few scans)
  // a client loses its oldest messages whenever the replay, as fast as the cores go, leaves its
  // reader behind, as under ThreadSanitizer on two cores (BadClients tests that loss).
  config.viewer.client_queue_bytes = 1 << 30;
  auto server = make_server(config);
  FoxgloveClient all(server->port());
  FoxgloveClient poses_only(server->port());  // several clients, each with its own subscriptions
  EXPECT_EQ(all.accepted_protocol, "foxglove.websocket.v1");
  EXPECT_EQ(all.server_info.at("op"), "serverInfo");
  ASSERT_EQ(all.advertise.at("op"), "advertise");
  std::map<std::string, std::string> schema_of;
  for (const auto& c : all.advertise.at("channels")) {
    EXPECT_EQ(c.at("encoding"), "json");
    EXPECT_TRUE(nlohmann::json::parse(c.at("schema").get<std::string>()).is_object()) << c.at("topic");
    schema_of[c.at("topic").get<std::string>()] = c.at("schemaName").get<std::string>();
  }
  EXPECT_EQ(schema_of["/liod/scan"], "foxglove.PointCloud");
  EXPECT_EQ(schema_of["/liod/map"], "foxglove.PointCloud");
  EXPECT_EQ(schema_of["/liod/pose/odom"], "foxglove.PoseInFrame");
  EXPECT_EQ(schema_of["/liod/pose/map"], "foxglove.PoseInFrame");
  EXPECT_EQ(schema_of["/liod/trajectory/odom"], "foxglove.PosesInFrame");
  EXPECT_EQ(schema_of["/liod/keyframes"], "foxglove.SceneUpdate");
  EXPECT_EQ(schema_of["/tf"], "foxglove.FrameTransform");
  EXPECT_EQ(schema_of["/liod/health"], "liod.Health");
  all.subscribe();
  poses_only.subscribe({"/liod/pose/"});
  all.start();
  poses_only.start();
  ASSERT_TRUE(test::wait_for([&] { return server->wants_scans(); }, std::chrono::seconds(5)));

  const auto run = replay_with(config, *drive, server);
  ASSERT_TRUE(run.error.empty()) << run.error;
  const auto truth = scan_positions(run);
  ASSERT_GT(truth.size(), 50U);
  const double last_time = truth.rbegin()->first;
  // The throttled channels go out within viewer.map_interval_s of the replay's end.
  ASSERT_TRUE(test::wait_for([&] {
    const auto t = all.messages("/liod/trajectory/odom");
    return all.count("/liod/pose/odom") >= truth.size() && !t.empty() &&
           std::abs(stamp_s(t.back().body.at("timestamp")) - last_time) < 1e-6;
  }, std::chrono::seconds(60))) << all.count("/liod/pose/odom") << " of " << truth.size() << " poses; dropped "
                                  << server->stats().messages_dropped << " messages, " << server->stats().posts_dropped << " posts";

  // Every scan pose, in order, where the replay put it.
  const auto poses = all.messages("/liod/pose/odom");
  EXPECT_EQ(poses.size(), truth.size());
  const auto pose_positions = replay_positions(poses, truth);
  ASSERT_EQ(pose_positions.size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_LT((position_of(poses[i].body.at("pose")) - pose_positions[i]).norm(), 1e-9);
    EXPECT_EQ(poses[i].body.at("frame_id"), "odom");
  }
  EXPECT_EQ(all.count("/liod/pose/map"), truth.size());
  EXPECT_EQ(poses_only.count("/liod/pose/odom"), truth.size());
  EXPECT_EQ(poses_only.count("/liod/scan"), 0U);
  EXPECT_EQ(poses_only.count("/liod/health"), 0U);

  // Scans: deskewed clouds around the vehicle (the drive's streets are within ~100 m).
  // A replay as fast as possible outruns the view's scans: those it cannot take are dropped.
  const auto scans = all.messages("/liod/scan");
  EXPECT_GE(scans.size(), 5U);
  EXPECT_LE(scans.size() + server->stats().posts_dropped, truth.size());
  const auto scan_at = replay_positions(scans, truth);
  ASSERT_EQ(scan_at.size(), scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const auto points = test::decode_points(scans[i].body);
    ASSERT_GT(points.size(), 1000U);
    std::vector<double> range;
    for (const auto& p : points) {
      ASSERT_TRUE(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]));
      range.push_back((Eigen::Vector3f(p[0], p[1], p[2]).cast<double>() - scan_at[i]).norm());
    }
    std::nth_element(range.begin(), range.begin() + static_cast<std::ptrdiff_t>(range.size() / 2), range.end());
    EXPECT_LT(range[range.size() / 2], 60.0);
  }

  // The local map: one point per 0.5 m voxel, none closer than that to another in its voxel.
  const auto maps = all.messages("/liod/map");
  ASSERT_FALSE(maps.empty());
  const auto map = test::decode_points(maps.back().body);
  EXPECT_GT(map.size(), 2000U);
  std::set<std::array<long, 3>> voxels;
  for (const auto& p : map) voxels.insert({voxel_cell(p, 0), voxel_cell(p, 1), voxel_cell(p, 2)});
  EXPECT_GE(static_cast<double>(voxels.size()), 0.99 * static_cast<double>(map.size()));  // float rounding at voxel faces

  // The last scan lies on the local map around it: both in the odometry frame, the scan's points
  // within a voxel or so of the map's (a scan left in the sensor frame, or placed with the wrong
  // pose, would not be).
  const auto last_scan = test::decode_points(scans.back().body);
  std::size_t on_map = 0;
  for (const auto& p : last_scan) {
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx) {
      for (int dy = -1; dy <= 1 && !near; ++dy) {
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          near = voxels.count({voxel_cell(p, 0) + dx, voxel_cell(p, 1) + dy, voxel_cell(p, 2) + dz}) != 0;
        }
      }
    }
    on_map += near ? 1 : 0;
  }
  EXPECT_GT(static_cast<double>(on_map), 0.8 * static_cast<double>(last_scan.size())) << on_map << " of " << last_scan.size();

  // The trajectory so far, ending at the last scan pose.
  const auto trajectory = all.messages("/liod/trajectory/odom").back().body.at("poses");
  ASSERT_GT(trajectory.size(), 10U);
  EXPECT_LT((position_of(trajectory.back()) - truth.rbegin()->second).norm(), 1e-9);
  EXPECT_FALSE(all.messages("/liod/trajectory/map").empty());

  // Keyframes as spheres at keyframe positions on the trajectory.
  const auto keyframes = all.messages("/liod/keyframes");
  ASSERT_FALSE(keyframes.empty());
  const auto spheres = keyframes.back().body.at("entities").at(0).at("spheres");
  EXPECT_GE(spheres.size(), 3U);

  // map -> odom -> base_link, and base_link where the pose is.
  std::set<std::string> links;
  for (const auto& m : all.messages("/tf")) links.insert(m.body.at("parent_frame_id").get<std::string>() + ">" + m.body.at("child_frame_id").get<std::string>());
  EXPECT_EQ(links, (std::set<std::string>{"map>odom", "odom>base_link"}));

  const auto health = all.messages("/liod/health");
  ASSERT_FALSE(health.empty());
  EXPECT_GT(health.back().body.at("odometry").at("scans").get<int>(), 0);
  EXPECT_TRUE(health.back().body.contains("latency_us"));
  const auto stats = server->stats();
  EXPECT_EQ(stats.messages_dropped, 0U);
  EXPECT_EQ(stats.connections, 2U);
  EXPECT_EQ(stats.bad_requests, 0U);
}

TEST(Foxglove, BadClientsDoNotStallOrChangeTheOdometry) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto reference = test::read_tum(test::reference_replay(*drive) / "scan.tum");
  Config config = test::drive_config(*drive);
  config.viewer.client_queue_bytes = 65536;
  auto server = make_server(config);
  const std::uint16_t port = server->port();

  // Stuck: subscribes to everything, never reads again.
  FoxgloveClient stuck(port);
  stuck.subscribe();
  // Garbage in every form a client can send; it stays connected and is told what was wrong.
  FoxgloveClient garbage(port);
  garbage.send_text("{not json");
  garbage.send_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":9999}]})");
  garbage.send_text(R"({"op":"subscribe","subscriptions":[{"id":"x"}]})");
  garbage.send_text(R"({"op":"unsubscribe","subscriptionIds":[77]})");
  garbage.send_text(R"({"op":"fly"})");
  garbage.send_binary(std::string("\x01\x02\x03", 3));
  garbage.subscribe({"/liod/pose/odom"});
  garbage.start();
  // Not a WebSocket at all, and a WebSocket of another protocol: refused.
  test::TcpConnection junk(port);
  junk.write(std::string("\x16\x03\x01 definitely not HTTP\r\n\r\n"));
  EXPECT_THROW(FoxgloveClient(port, "other.protocol"), std::exception);
  // Gone in the middle of a frame: the first bytes of a masked text frame, then closed.
  {
    FoxgloveClient half(port);
    half.subscribe();
  }
  {
    test::TcpConnection s(port);
    const std::string upgrade = "GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                                "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n";
    s.write(upgrade);
    s.read_until("\r\n\r\n", 16384);
    s.write(std::string("\x81\xFE\x01\x00\x11\x22", 6));  // 256-byte frame, 2 sent
  }

  const auto run = replay_with(config, *drive, server);
  ASSERT_TRUE(run.error.empty()) << run.error;
  // The same poses as the replay without a viewer, bit for bit (the replay is deterministic).
  std::vector<const PoseEvent*> scan_poses;
  for (const auto& p : run.poses) {
    if (p.event.message.type == pose::MessageType::ScanPose) scan_poses.push_back(&p.event);
  }
  ASSERT_EQ(scan_poses.size(), reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_NEAR(scan_poses[i]->message.position.x(), reference[i].x, 1e-6);
    EXPECT_NEAR(scan_poses[i]->message.position.y(), reference[i].y, 1e-6);
  }
  ASSERT_TRUE(test::wait_for([&] { return garbage.count("/liod/pose/odom") == reference.size(); }, std::chrono::seconds(60)))
      << garbage.count("/liod/pose/odom") << " of " << reference.size();
  EXPECT_GE(garbage.statuses().size(), 6U);
  for (const auto& s : garbage.statuses()) EXPECT_EQ(s.at("level"), 2) << s.dump();
  const auto stats = server->stats();
  EXPECT_GE(stats.bad_requests, 6U);
  EXPECT_GE(stats.refused, 2U);             // the junk and the other protocol
  EXPECT_GT(stats.messages_dropped, 0U);    // the stuck client's oldest
  // The ones that left are gone; the stuck one and the garbage one are still served.
  EXPECT_TRUE(test::wait_for([&] { return server->stats().clients == 2; }, std::chrono::seconds(5))) << server->stats().clients;
}

TEST(Foxglove, ListensOnlyWhereConfigured) {
  Config config;
  config.viewer.bind_address = "not-an-address";
  try {
    FoxgloveServer s(config.viewer, config.extrinsics, 0);
    FAIL() << "a bad address was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("viewer.bind_address not-an-address"), std::string::npos) << e.what();
  }
  config.viewer.bind_address = "127.0.0.1";
  FoxgloveServer first(config.viewer, config.extrinsics, 0);
  EXPECT_THROW(FoxgloveServer(config.viewer, config.extrinsics, first.port()), std::runtime_error);  // port in use
}

}  // namespace
}  // namespace liod
