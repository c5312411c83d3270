#include "liod/daemon/foxglove_server.hpp"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "foxglove_server_impl.hpp"

namespace liod {

using namespace foxglove;  // the channels and the server's constants (foxglove_server_impl.hpp)

// ---- FoxgloveServer::Impl ---------------------------------------------------------------------
FoxgloveServer::Impl::Impl(const ViewerConfig& cfg, const ExtrinsicsConfig& ext, std::uint16_t port)
    : config(cfg), extrinsics(ext), view(cfg) {
  const std::string where = "viewer.bind_address " + config.bind_address + " port " + std::to_string(port);
  beast::error_code ec;
  const auto address = asio::ip::make_address(config.bind_address, ec);
  if (ec) throw std::runtime_error(where + ": not an IP address");
  const tcp::endpoint endpoint(address, port);
  acceptor.open(endpoint.protocol(), ec);
  if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error(where + ": cannot listen: " + ec.message());
  bound_port = acceptor.local_endpoint().port();
  session_id = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
  accept();
  on_tick();
  thread = std::thread([this] {
    ::pthread_setname_np(::pthread_self(), "liod-viewer");
    ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kViewerNice);
    for (;;) {
      try {
        ioc.run();
        return;
      } catch (const std::exception& e) {
        spdlog::error("live view: {}", e.what());  // a viewer's fault never ends the daemon
      }
    }
  });
}

FoxgloveServer::Impl::~Impl() {
  ioc.stop();
  if (thread.joinable()) thread.join();
  sessions.clear();  // the pending handlers that still hold sessions go with ioc
}

template <class F>
void FoxgloveServer::Impl::post(F&& task, std::atomic<int>& pending, int limit) {
  if (pending.fetch_add(1, std::memory_order_relaxed) >= limit) {
    pending.fetch_sub(1, std::memory_order_relaxed);
    posts_dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  asio::post(ioc, [this, &pending, task = std::forward<F>(task)]() mutable {
    pending.fetch_sub(1, std::memory_order_relaxed);
    task();
  });
}

void FoxgloveServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      if (sessions.size() >= static_cast<std::size_t>(config.max_clients)) {
        ++refused;  // the socket closes as it goes out of scope
      } else {
        sessions.push_back(std::make_shared<Session>(std::move(socket), *this));
        clients.store(sessions.size());
        sessions.back()->start();
      }
    }
    accept();
  });
}

void FoxgloveServer::Impl::remove(Session* session) {
  std::erase_if(sessions, [session](const auto& s) { return s.get() == session; });
  clients.store(sessions.size());
  update_interest();
}

void FoxgloveServer::Impl::update_interest() { scans_wanted.store(subscribed(foxglove::kScan), std::memory_order_relaxed); }

bool FoxgloveServer::Impl::subscribed(ChannelId channel) const {
  return std::any_of(sessions.begin(), sessions.end(), [channel](const auto& s) { return s->subscribed(channel); });
}

void FoxgloveServer::Impl::broadcast(ChannelId channel, double time, std::string payload) {
  const auto shared = std::make_shared<const std::string>(std::move(payload));
  const std::uint64_t ns = foxglove::time_ns(time);
  for (const auto& s : std::vector<std::shared_ptr<Session>>(sessions)) s->send_message(channel, ns, shared);
}

// The throttled channels: at most once per viewer.map_interval_s, when changed and watched.
void FoxgloveServer::Impl::on_tick() {
  const double t = view.latest_time();
  if (map_dirty && subscribed(foxglove::kMap)) {
    broadcast(foxglove::kMap, t, foxglove::point_cloud_json(t, "odom", view.local_map()));
    map_dirty = false;
  }
  if (trajectory_dirty) {
    if (subscribed(foxglove::kTrajectoryOdom)) broadcast(foxglove::kTrajectoryOdom, t, foxglove::poses_in_frame_json(t, "odom", view.trajectory(false)));
    if (subscribed(foxglove::kTrajectoryMap)) broadcast(foxglove::kTrajectoryMap, t, foxglove::poses_in_frame_json(t, "map", view.trajectory(true)));
    trajectory_dirty = false;
  }
  if (keyframes_dirty && subscribed(foxglove::kKeyframes)) {
    const ViewGraph g = view.keyframes();
    broadcast(foxglove::kKeyframes, t, foxglove::keyframes_scene_json(t, view.has_graph() ? "map" : "odom", g.keyframes, g.loops));
    keyframes_dirty = false;
  }
  tick.expires_after(std::chrono::duration_cast<asio::steady_timer::duration>(std::chrono::duration<double>(config.map_interval_s)));
  tick.async_wait([this](beast::error_code ec) {
    if (!ec) on_tick();
  });
}

void FoxgloveServer::Impl::handle_pose(const pose::PoseMessage& m) {
  view.add_pose(m);
  trajectory_dirty = true;
  if (subscribed(foxglove::kPoseOdom)) broadcast(foxglove::kPoseOdom, m.time, foxglove::pose_in_frame_json(m.time, "odom", m.position, m.orientation));
  if (subscribed(foxglove::kPoseMap)) broadcast(foxglove::kPoseMap, m.time, foxglove::pose_in_frame_json(m.time, "map", m.map_position, m.map_orientation));
  if (!subscribed(foxglove::kTransforms)) return;
  // REP 105's chain: map -> odom (the backend's correction) -> base_link (the body).
  const Eigen::Isometry3d odom_body = Eigen::Translation3d(m.position) * m.orientation;
  const Eigen::Isometry3d map_body = Eigen::Translation3d(m.map_position) * m.map_orientation;
  const Eigen::Isometry3d map_odom = map_body * odom_body.inverse();
  broadcast(foxglove::kTransforms, m.time,
            foxglove::frame_transform_json(m.time, "map", "odom", map_odom.translation(), Eigen::Quaterniond(map_odom.linear())));
  broadcast(foxglove::kTransforms, m.time, foxglove::frame_transform_json(m.time, "odom", "base_link", m.position, m.orientation));
}

// ---- FoxgloveServer ---------------------------------------------------------------------------
FoxgloveServer::FoxgloveServer(const ViewerConfig& config, const ExtrinsicsConfig& extrinsics, std::uint16_t port)
    : impl_(std::make_unique<Impl>(config, extrinsics, port)) {
  spdlog::info("live view: Foxglove WebSocket server on ws://{}:{}", config.bind_address, this->port());
}

FoxgloveServer::~FoxgloveServer() = default;

std::uint16_t FoxgloveServer::port() const { return impl_->bound_port; }

bool FoxgloveServer::wants_scans() const { return impl_->scans_wanted.load(std::memory_order_relaxed); }

void FoxgloveServer::post_scan(ViewScan scan) {
  Impl& s = *impl_;
  s.post([&s, scan = std::move(scan)] {
    if (!s.subscribed(foxglove::kScan)) return;
    s.broadcast(foxglove::kScan, scan.state.time,
                foxglove::point_cloud_json(scan.state.time, "odom", foxglove::view_points(scan, s.extrinsics, s.config.scan_voxel_m)));
  }, s.pending_scans, kMaxPendingScans);
}

void FoxgloveServer::post_pose(const pose::PoseMessage& scan_pose) {
  Impl& s = *impl_;
  s.post([&s, m = scan_pose] { s.handle_pose(m); }, s.pending_posts, kMaxPendingPosts);
}

void FoxgloveServer::post_keyframe(std::shared_ptr<const Keyframe> keyframe, std::vector<std::uint64_t> window_ids) {
  Impl& s = *impl_;
  s.post([&s, k = std::move(keyframe), ids = std::move(window_ids)]() mutable {
    s.view.add_keyframe(std::move(k), ids);
    s.map_dirty = s.keyframes_dirty = true;
  }, s.pending_posts, kMaxPendingPosts);
}

void FoxgloveServer::post_graph(ViewGraph graph) {
  Impl& s = *impl_;
  s.post([&s, g = std::move(graph)]() mutable {
    s.view.set_graph(std::move(g));
    s.keyframes_dirty = true;
  }, s.pending_posts, kMaxPendingPosts);
}

void FoxgloveServer::post_health(std::string health_json) {
  Impl& s = *impl_;
  s.post([&s, h = std::move(health_json)]() mutable { s.broadcast(foxglove::kHealth, s.view.latest_time(), std::move(h)); },
         s.pending_posts, kMaxPendingPosts);
}

FoxgloveServerStats FoxgloveServer::stats() const {
  const Impl& s = *impl_;
  return {s.clients.load(), s.connections.load(), s.refused.load(), s.sent.load(), s.dropped.load(), s.posts_dropped.load(),
          s.bad_requests.load()};
}

}  // namespace liod
