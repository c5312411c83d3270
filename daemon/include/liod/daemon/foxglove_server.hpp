#pragma once
// The live view: a Foxglove WebSocket server (subprotocol foxglove.websocket.v1) that Foxglove
// Studio connects to (ws://HOST:PORT). It runs on an io thread of its own; the pipeline's threads
// hand it copies through the post_* calls, which never wait: each only queues a task for the io
// thread, and drops it (counted) when that thread is that far behind. Everything a viewer costs
// (deskewing the scan for the view, downsampling, JSON, sending) is paid on the io thread.
//
// Channels (JSON encoding, Foxglove's schemas; docs/design.md "Live view"):
//   /liod/scan        foxglove.PointCloud     each scan deskewed, in the odometry frame (odom)
//   /liod/map         foxglove.PointCloud     the local map (the window's keyframes), throttled
//   /liod/pose/odom   foxglove.PoseInFrame    each scan pose, odometry frame
//   /liod/pose/map    foxglove.PoseInFrame    each scan pose, map frame (loop-corrected)
//   /liod/trajectory/odom, /liod/trajectory/map  foxglove.PosesInFrame  the drive so far, throttled
//   /liod/keyframes   foxglove.SceneUpdate    keyframes (map frame) and loop closures, throttled
//   /tf               foxglove.FrameTransform map -> odom -> base_link
//   /liod/health      liod.Health             the pose socket's health figures
//
// Boost.Beast stays in foxglove_server.cpp: this header is included by the pipeline.

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/daemon/daemon_config.hpp"
#include "liod/daemon/pose_protocol.hpp"
#include "liod/keyframe.hpp"
#include "liod/types.hpp"

namespace liod {

/// A scan for the view: its points as the LiDAR measured them and the scan's end state.
struct ViewScan {
  std::shared_ptr<const Scan> scan;
  NavState state;                                            ///< body at the scan's end (odometry frame)
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();   ///< body frame, for the deskew
};

/// The backend's graph for the view: every keyframe's optimised position (map frame), the loops
/// closed between them (node indices).
struct ViewGraph {
  std::vector<Eigen::Vector3d> keyframes;
  std::vector<std::pair<std::size_t, std::size_t>> loops;
};

/// What the server did, for tests and the benchmark.
struct FoxgloveServerStats {
  std::uint64_t clients = 0;           ///< connected now
  std::uint64_t connections = 0;       ///< accepted since start (refused ones not counted)
  std::uint64_t refused = 0;           ///< over viewer.max_clients, or not a foxglove.websocket.v1 handshake
  std::uint64_t messages_sent = 0;     ///< message data frames written
  std::uint64_t messages_dropped = 0;  ///< dropped from a slow client's queue (oldest first)
  std::uint64_t posts_dropped = 0;     ///< pipeline posts dropped with the io thread behind
  std::uint64_t bad_requests = 0;      ///< client messages answered with an error status
};

class FoxgloveServer {
 public:
  /// Listens on config.bind_address : `port` (0: an ephemeral port, see port()). Throws
  /// std::runtime_error with the address named when it cannot.
  FoxgloveServer(const ViewerConfig& config, const ExtrinsicsConfig& extrinsics, std::uint16_t port);
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  std::uint16_t port() const;
  /// Whether any client subscribes to the scan channel: the odometry copies a scan only then.
  bool wants_scans() const;

  // Any thread; never waits for the io thread.
  void post_scan(ViewScan scan);
  void post_pose(const pose::PoseMessage& scan_pose);
  /// A new keyframe and the ids of the keyframes now in the odometry's window (the local map).
  void post_keyframe(std::shared_ptr<const Keyframe> keyframe, std::vector<std::uint64_t> window_ids);
  void post_graph(ViewGraph graph);
  void post_health(std::string health_json);

  FoxgloveServerStats stats() const;

  class Impl;  // the io thread and its sessions (foxglove_server.cpp)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace liod
