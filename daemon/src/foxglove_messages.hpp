#pragma once
// The live view's channels and their messages in Foxglove's JSON encoding (foxglove_server.hpp):
// the schemas advertised, each message's JSON, and the view's own state on the server's io thread
// (the local map's keyframes, the trajectories, the backend's graph). No sockets here.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "liod/daemon/foxglove_server.hpp"

namespace liod::foxglove {

enum ChannelId : std::uint32_t {
  kScan = 1,
  kMap,
  kPoseOdom,
  kPoseMap,
  kTrajectoryOdom,
  kTrajectoryMap,
  kKeyframes,
  kTransforms,
  kHealth,
  kChannelCount = kHealth,
};

/// The advertise message listing every channel with its JSON schema.
std::string advertise_json();
/// The serverInfo message.
std::string server_info_json(const std::string& session_id);
/// A status message (level 0 info, 1 warning, 2 error).
std::string status_json(int level, const std::string& message);

/// The message-data frame's header: opcode 1, subscription id and log time (ns), little-endian.
std::array<std::uint8_t, 13> message_header(std::uint32_t subscription, std::uint64_t log_time_ns);
/// Data time (s) as the log time in ns; negative times as 0.
std::uint64_t time_ns(double t);

std::string pose_in_frame_json(double t, const char* frame, const Eigen::Vector3d& p, const Eigen::Quaterniond& q);
std::string frame_transform_json(double t, const char* parent, const char* child, const Eigen::Vector3d& p,
                                 const Eigen::Quaterniond& q);
struct StampedPosition {
  double time;
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;
};
std::string poses_in_frame_json(double t, const char* frame, const std::vector<StampedPosition>& poses);
/// x, y, z as FLOAT32, base64 (the schema's contentEncoding).
std::string point_cloud_json(double t, const char* frame, const std::vector<Eigen::Vector3f>& points);
/// Keyframes as spheres and the loops as lines, one entity.
std::string keyframes_scene_json(double t, const char* frame, const std::vector<Eigen::Vector3d>& keyframes,
                                 const std::vector<std::pair<std::size_t, std::size_t>>& loops);

/// The scan's points in the odometry frame, deskewed with the scan's end velocity and angular
/// rate (constant over the sweep: the view needs no IMU) and downsampled to `voxel_m` (0: all).
std::vector<Eigen::Vector3f> view_points(const ViewScan& scan, const ExtrinsicsConfig& extrinsics, double voxel_m);

/// The view's state, kept on the io thread: what the throttled channels are made of.
class ViewState {
 public:
  explicit ViewState(const ViewerConfig& config) : config_(config) {}
  void add_pose(const pose::PoseMessage& m);
  void add_keyframe(std::shared_ptr<const Keyframe> keyframe, const std::vector<std::uint64_t>& window_ids);
  void set_graph(ViewGraph graph) { graph_ = std::move(graph); }

  double latest_time() const { return latest_time_; }
  /// The window's keyframes' points, downsampled to viewer.map_voxel_m.
  std::vector<Eigen::Vector3f> local_map() const;
  const std::vector<StampedPosition>& trajectory(bool map_frame) const { return map_frame ? map_ : odom_; }
  /// The backend's keyframes (map frame) and loops; without a backend the odometry's keyframes.
  ViewGraph keyframes() const;
  bool has_graph() const { return !graph_.keyframes.empty(); }

 private:
  void decimate();

  ViewerConfig config_;
  std::map<std::uint64_t, std::shared_ptr<const Keyframe>> window_;
  std::vector<Eigen::Vector3d> odometry_keyframes_;
  std::vector<StampedPosition> odom_, map_;
  ViewGraph graph_;
  double latest_time_ = 0.0;
};

}  // namespace liod::foxglove
