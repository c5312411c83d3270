#include "foxglove_messages.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "liod/deskew.hpp"
#include "liod/voxel_grid.hpp"

namespace liod::foxglove {
namespace {

using nlohmann::json;

// ---- JSON schemas (the parts of Foxglove's foxglove/schemas jsonschema files the messages use;
// Studio picks its panels by schemaName and decodes `data` by the schema's contentEncoding) ----
json number() { return {{"type", "number"}}; }
json object(json properties) { return {{"type", "object"}, {"properties", std::move(properties)}}; }
json time_schema() {
  return object({{"sec", {{"type", "integer"}, {"minimum", 0}}}, {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}});
}
json vector3_schema() { return object({{"x", number()}, {"y", number()}, {"z", number()}}); }
json quaternion_schema() { return object({{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}}); }
json pose_schema() { return object({{"position", vector3_schema()}, {"orientation", quaternion_schema()}}); }
json color_schema() { return object({{"r", number()}, {"g", number()}, {"b", number()}, {"a", number()}}); }
json titled(const char* title, json schema) {
  schema["title"] = title;
  return schema;
}

json point_cloud_schema() {
  json field = object({{"name", {{"type", "string"}}}, {"offset", {{"type", "integer"}, {"minimum", 0}}},
                       {"type", {{"type", "integer"}}}});
  return object({{"timestamp", time_schema()},
                 {"frame_id", {{"type", "string"}}},
                 {"pose", pose_schema()},
                 {"point_stride", {{"type", "integer"}, {"minimum", 0}}},
                 {"fields", {{"type", "array"}, {"items", field}}},
                 {"data", {{"type", "string"}, {"contentEncoding", "base64"}}}});
}

json pose_in_frame_schema() { return object({{"timestamp", time_schema()}, {"frame_id", {{"type", "string"}}}, {"pose", pose_schema()}}); }

json poses_in_frame_schema() {
  return object({{"timestamp", time_schema()}, {"frame_id", {{"type", "string"}}},
                 {"poses", {{"type", "array"}, {"items", pose_schema()}}}});
}

json frame_transform_schema() {
  return object({{"timestamp", time_schema()}, {"parent_frame_id", {{"type", "string"}}}, {"child_frame_id", {{"type", "string"}}},
                 {"translation", vector3_schema()}, {"rotation", quaternion_schema()}});
}

json scene_update_schema() {
  json sphere = object({{"pose", pose_schema()}, {"size", vector3_schema()}, {"color", color_schema()}});
  json line = object({{"type", {{"type", "integer"}}},
                      {"pose", pose_schema()},
                      {"thickness", number()},
                      {"scale_invariant", {{"type", "boolean"}}},
                      {"points", {{"type", "array"}, {"items", vector3_schema()}}},
                      {"color", color_schema()}});
  json entity = object({{"timestamp", time_schema()},
                        {"frame_id", {{"type", "string"}}},
                        {"id", {{"type", "string"}}},
                        {"frame_locked", {{"type", "boolean"}}},
                        {"spheres", {{"type", "array"}, {"items", sphere}}},
                        {"lines", {{"type", "array"}, {"items", line}}}});
  return object({{"deletions", {{"type", "array"}, {"items", object({{"type", {{"type", "integer"}}}, {"id", {{"type", "string"}}}})}}},
                 {"entities", {{"type", "array"}, {"items", entity}}}});
}

json channel(ChannelId id, const char* topic, const char* schema_name, const json& schema) {
  return {{"id", id},
          {"topic", topic},
          {"encoding", "json"},
          {"schemaName", schema_name},
          {"schemaEncoding", "jsonschema"},
          {"schema", titled(schema_name, schema).dump()}};
}

json stamp(double t) {
  const std::uint64_t ns = time_ns(t);
  return {{"sec", ns / 1000000000ULL}, {"nsec", ns % 1000000000ULL}};
}
json vec(const Eigen::Vector3d& p) { return {{"x", p.x()}, {"y", p.y()}, {"z", p.z()}}; }
json quat(const Eigen::Quaterniond& q) { return {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}; }
json pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) { return {{"position", vec(p)}, {"orientation", quat(q)}}; }
json color(double r, double g, double b, double a) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }

std::string base64(const std::uint8_t* data, std::size_t n) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < n; i += 3) {
    const std::uint32_t v = (std::uint32_t{data[i]} << 16) | (std::uint32_t{data[i + 1]} << 8) | data[i + 2];
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(v >> s) & 63U]);
  }
  if (i < n) {
    const std::uint32_t v = (std::uint32_t{data[i]} << 16) | (i + 1 < n ? std::uint32_t{data[i + 1]} << 8 : 0U);
    out.push_back(kAlphabet[(v >> 18) & 63U]);
    out.push_back(kAlphabet[(v >> 12) & 63U]);
    out.push_back(i + 1 < n ? kAlphabet[(v >> 6) & 63U] : '=');
    out.push_back('=');
  }
  return out;
}

// Little-endian whatever the host (the spec's byte order; ARM64 and x86-64 alike).
void put_le(std::uint8_t* out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

}  // namespace

std::string advertise_json() {
  const json health = object({{"version", {{"type", "integer"}}}, {"lidar", {{"type", "object"}}}, {"imu", {{"type", "object"}}},
                              {"odometry", {{"type", "object"}}}, {"latency_us", {{"type", "object"}}}});
  json channels = json::array({
      channel(kScan, "/liod/scan", "foxglove.PointCloud", point_cloud_schema()),
      channel(kMap, "/liod/map", "foxglove.PointCloud", point_cloud_schema()),
      channel(kPoseOdom, "/liod/pose/odom", "foxglove.PoseInFrame", pose_in_frame_schema()),
      channel(kPoseMap, "/liod/pose/map", "foxglove.PoseInFrame", pose_in_frame_schema()),
      channel(kTrajectoryOdom, "/liod/trajectory/odom", "foxglove.PosesInFrame", poses_in_frame_schema()),
      channel(kTrajectoryMap, "/liod/trajectory/map", "foxglove.PosesInFrame", poses_in_frame_schema()),
      channel(kKeyframes, "/liod/keyframes", "foxglove.SceneUpdate", scene_update_schema()),
      channel(kTransforms, "/tf", "foxglove.FrameTransform", frame_transform_schema()),
      channel(kHealth, "/liod/health", "liod.Health", health),
  });
  return json{{"op", "advertise"}, {"channels", std::move(channels)}}.dump();
}

std::string server_info_json(const std::string& session_id) {
  return json{{"op", "serverInfo"}, {"name", "liod"}, {"capabilities", json::array()},
              {"metadata", json::object()}, {"sessionId", session_id}}
      .dump();
}

std::string status_json(int level, const std::string& message) {
  // Client text is echoed in errors: dump() escapes it, and invalid UTF-8 is replaced, not thrown.
  return json{{"op", "status"}, {"level", level}, {"message", message}}.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::array<std::uint8_t, 13> message_header(std::uint32_t subscription, std::uint64_t log_time_ns) {
  std::array<std::uint8_t, 13> h{};
  h[0] = 0x01;
  put_le(h.data() + 1, subscription, 4);
  put_le(h.data() + 5, log_time_ns, 8);
  return h;
}

std::uint64_t time_ns(double t) {
  if (!(t > 0.0)) return 0;
  return static_cast<std::uint64_t>(std::llround(t * 1e9));
}

std::string pose_in_frame_json(double t, const char* frame, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return json{{"timestamp", stamp(t)}, {"frame_id", frame}, {"pose", pose(p, q)}}.dump();
}

std::string frame_transform_json(double t, const char* parent, const char* child, const Eigen::Vector3d& p,
                                 const Eigen::Quaterniond& q) {
  return json{{"timestamp", stamp(t)}, {"parent_frame_id", parent}, {"child_frame_id", child},
              {"translation", vec(p)}, {"rotation", quat(q)}}
      .dump();
}

std::string poses_in_frame_json(double t, const char* frame, const std::vector<StampedPosition>& poses) {
  json list = json::array();
  for (const auto& s : poses) list.push_back(pose(s.position, s.orientation));
  return json{{"timestamp", stamp(t)}, {"frame_id", frame}, {"poses", std::move(list)}}.dump();
}

std::string point_cloud_json(double t, const char* frame, const std::vector<Eigen::Vector3f>& points) {
  std::vector<std::uint8_t> data(points.size() * 12);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &points[i][k], 4);
      put_le(data.data() + i * 12 + static_cast<std::size_t>(k) * 4, bits, 4);
    }
  }
  constexpr int kFloat32 = 7;  // foxglove.NumericType
  json fields = json::array();
  for (int k = 0; k < 3; ++k) fields.push_back({{"name", std::string(1, static_cast<char>('x' + k))}, {"offset", 4 * k}, {"type", kFloat32}});
  return json{{"timestamp", stamp(t)},
              {"frame_id", frame},
              {"pose", pose(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity())},
              {"point_stride", 12},
              {"fields", std::move(fields)},
              {"data", base64(data.data(), data.size())}}
      .dump();
}

std::string keyframes_scene_json(double t, const char* frame, const std::vector<Eigen::Vector3d>& keyframes,
                                 const std::vector<std::pair<std::size_t, std::size_t>>& loops) {
  const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
  json spheres = json::array();
  for (const auto& k : keyframes) {
    spheres.push_back({{"pose", pose(k, identity)}, {"size", vec(Eigen::Vector3d::Constant(0.8))}, {"color", color(0.2, 0.6, 1.0, 1.0)}});
  }
  json loop_points = json::array();
  for (const auto& [a, b] : loops) {
    if (a >= keyframes.size() || b >= keyframes.size()) continue;
    loop_points.push_back(vec(keyframes[a]));
    loop_points.push_back(vec(keyframes[b]));
  }
  constexpr int kLineList = 2;  // foxglove.LinePrimitive type: pairs of points
  json lines = json::array({{{"type", kLineList}, {"pose", pose(Eigen::Vector3d::Zero(), identity)}, {"thickness", 0.3},
                             {"scale_invariant", false}, {"points", std::move(loop_points)}, {"color", color(1.0, 0.3, 0.1, 1.0)}}});
  json entity = {{"timestamp", stamp(t)}, {"frame_id", frame}, {"id", "keyframes"}, {"frame_locked", false},
                 {"spheres", std::move(spheres)}, {"lines", std::move(lines)}};
  return json{{"deletions", json::array()}, {"entities", json::array({std::move(entity)})}}.dump();
}

std::vector<Eigen::Vector3f> view_points(const ViewScan& view, const ExtrinsicsConfig& extrinsics, double voxel_m) {
  const Scan& scan = *view.scan;
  const double t0 = scan.start_time + extrinsics.lidar_time_offset_s;
  const double t1 = scan.end_time + extrinsics.lidar_time_offset_s;
  const PoseTable relative = deskew_trajectory(DeskewMode::kConstantVelocity, t0, t1, view.state, view.state, {}, view.angular_rate);
  const Pose lidar_to_imu{extrinsics.lidar_to_imu_rotation, extrinsics.lidar_to_imu_translation};
  const Pose world_from_end{Eigen::Quaterniond(view.state.rotation), view.state.position};
  std::vector<Eigen::Vector3d> world;
  world.reserve(scan.points.size());
  for (const auto& p : scan.points) {
    if (!std::isfinite(p.x) || (p.x == 0.0F && p.y == 0.0F && p.z == 0.0F)) continue;
    const Eigen::Vector3d body = lidar_to_imu * Eigen::Vector3f(p.x, p.y, p.z).cast<double>();
    world.push_back(world_from_end * (relative.at(t0 + static_cast<double>(p.time)) * body));
  }
  if (voxel_m > 0.0) world = voxel_downsample(world, voxel_m);
  std::vector<Eigen::Vector3f> out(world.size());
  std::transform(world.begin(), world.end(), out.begin(), [](const Eigen::Vector3d& p) { return p.cast<float>(); });
  return out;
}

// ---- ViewState ----------------------------------------------------------------------------------
void ViewState::add_pose(const pose::PoseMessage& m) {
  latest_time_ = m.time;
  auto append = [](std::vector<StampedPosition>& v, const StampedPosition& s) {
    // A pose every 0.5 m (and the latest): the drive's shape, not its scan rate.
    if (v.size() >= 2 && (v[v.size() - 2].position - s.position).norm() < 0.5) v.back() = s;
    else v.push_back(s);
  };
  append(odom_, {m.time, m.position, m.orientation});
  append(map_, {m.time, m.map_position, m.map_orientation});
  decimate();
}

// The trajectories stay bounded on a drive of any length: beyond 20000 poses every other goes.
void ViewState::decimate() {
  constexpr std::size_t kMaxPoses = 20000;
  for (auto* v : {&odom_, &map_}) {
    if (v->size() <= kMaxPoses) continue;
    std::size_t j = 0;
    for (std::size_t i = 0; i < v->size(); i += 2) (*v)[j++] = (*v)[i];
    if (j == 0 || (*v)[j - 1].time != v->back().time) (*v)[j++] = v->back();
    v->resize(j);
  }
}

void ViewState::add_keyframe(std::shared_ptr<const Keyframe> keyframe, const std::vector<std::uint64_t>& window_ids) {
  odometry_keyframes_.push_back(keyframe->state.position);
  window_[keyframe->id] = std::move(keyframe);
  for (auto it = window_.begin(); it != window_.end();) {
    it = std::find(window_ids.begin(), window_ids.end(), it->first) == window_ids.end() ? window_.erase(it) : std::next(it);
  }
}

std::vector<Eigen::Vector3f> ViewState::local_map() const {
  std::vector<Eigen::Vector3d> points;
  for (const auto& [id, k] : window_) {
    points.insert(points.end(), k->planes_world.begin(), k->planes_world.end());
    points.insert(points.end(), k->edges_world.begin(), k->edges_world.end());
  }
  points = voxel_downsample(points, config_.map_voxel_m);
  std::vector<Eigen::Vector3f> out(points.size());
  std::transform(points.begin(), points.end(), out.begin(), [](const Eigen::Vector3d& p) { return p.cast<float>(); });
  return out;
}

ViewGraph ViewState::keyframes() const {
  if (!graph_.keyframes.empty()) return graph_;
  return {odometry_keyframes_, {}};
}

}  // namespace liod::foxglove
