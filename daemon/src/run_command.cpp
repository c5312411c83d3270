#include "liod/daemon/run_command.hpp"

#include <linux/capability.h>
#include <poll.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/signalfd.h>
#include <sys/syscall.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <thread>

#include "liod/daemon/foxglove_server.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_client.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/pcap_writer.hpp"
#include "liod/drivers/time_sync.hpp"

namespace liod {
namespace {

/// Writes what the drivers receive, off their threads: the taps only copy into SPSC rings (a
/// full ring drops and counts, never stalls a driver), and this thread does the file I/O. A
/// write that fails (a full disk) stops the recording only: logged, counted, and reported by
/// failed() so that `liod record` exits non-zero; the daemon runs on.
class Recorder {
 public:
  explicit Recorder(const std::filesystem::path& dir)
      : pcap_(dir / "lidar.pcap"), imu_(dir / "imu.csv"), packets_(8192, &wakeup_), samples_(8192, &wakeup_),
        thread_([this] { run(); }) {}
  ~Recorder() { finish(); }
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Stops the writer thread, flushes the files and logs the totals; false when the recording
  /// is incomplete (a write failed).
  bool finish() {
    if (finished_) return !failed();
    finished_ = true;
    stop_.store(true);
    wakeup_.notify();
    thread_.join();
    if (!failed()) guarded([this] {
      pcap_.flush();
      imu_.flush();
    });
    spdlog::log(failed() ? spdlog::level::err : spdlog::level::info,
                "record: {} packets, {} IMU samples written; {} packets and {} samples dropped (disk too slow), {} "
                "non-finite samples not written{}",
                packets_written_, samples_written_, packets_.drops(), samples_.drops(), non_finite_samples_,
                failed() ? "; recording stopped early: " + error_ : std::string());
    return !failed();
  }
  void packet(std::span<const std::uint8_t> payload, std::int64_t time_ns, std::uint16_t dst_port) {
    if (payload.size() > kMaxPayload || failed_.load(std::memory_order_relaxed)) return;
    item_.time_ns = time_ns;
    item_.dst_port = dst_port;
    item_.length = static_cast<std::uint16_t>(payload.size());
    std::copy(payload.begin(), payload.end(), item_.data.begin());
    packets_.try_push(item_);
  }
  void sample(const ImuSample& s) {
    if (failed_.load(std::memory_order_relaxed)) return;
    ImuSample copy = s;
    samples_.try_push(copy);
  }
  /// A write failed; the recording ended there.
  bool failed() const noexcept { return failed_.load(); }

 private:
  static constexpr std::size_t kMaxPayload = 1500;
  struct Packet {
    std::int64_t time_ns = 0;
    std::uint16_t dst_port = 0;
    std::uint16_t length = 0;
    std::array<std::uint8_t, kMaxPayload> data{};
  };
  /// Runs a write; a failure ends the recording (the writers throw on any I/O error).
  template <typename Write>
  bool guarded(Write&& write) {
    try {
      write();
      return true;
    } catch (const std::exception& e) {
      error_ = e.what();
      failed_.store(true);
      spdlog::error("record: {}; recording stopped (the daemon runs on)", error_);
      return false;
    }
  }
  bool write_pending() {
    Packet p;
    ImuSample s;
    bool any = false;
    while (packets_.try_pop(p)) {
      drivers::UdpDatagram d;
      d.capture_time_ns = p.time_ns;
      d.src_ip = 0xC0A801C8;  // 192.168.1.200, the sensor's factory address (the source is not kept)
      d.dst_ip = 0xC0A80166;  // 192.168.1.102
      d.src_port = p.dst_port;
      d.dst_port = p.dst_port;
      d.payload = std::span<const std::uint8_t>(p.data.data(), p.length);
      if (!guarded([&] { pcap_.write(d); })) return false;
      ++packets_written_;
      any = true;
    }
    while (samples_.try_pop(s)) {
      any = true;
      // The IMU log's reader refuses NaN and infinity (as the odometry does): such a sample
      // from a driver is left out, not a reason to stop recording.
      if (!s.gyro.allFinite() || !s.accel.allFinite() || !std::isfinite(s.time)) {
        ++non_finite_samples_;
        continue;
      }
      if (!guarded([&] { imu_.write(s); })) return false;
      ++samples_written_;
    }
    return any;
  }
  void run() {
    while (!failed()) {
      if (!write_pending()) {
        if (failed() || stop_.load()) return;
        wakeup_.wait(std::chrono::milliseconds(100));
      }
    }
  }
  drivers::PcapWriter pcap_;
  drivers::ImuCsvWriter imu_;
  drivers::Notifier wakeup_;
  drivers::SpscRing<Packet> packets_;
  drivers::SpscRing<ImuSample> samples_;
  Packet item_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> failed_{false};
  bool finished_ = false;
  std::string error_;  // written by the recorder thread before failed_, read after the join
  std::uint64_t packets_written_ = 0, samples_written_ = 0, non_finite_samples_ = 0;
  std::thread thread_;
};

/// SIGTERM/SIGINT/SIGHUP arrive on a descriptor instead of an asynchronous handler: no global
/// flag, and the main loop's poll() wakes at once. Blocked before any thread starts, so every
/// thread inherits the mask and only this descriptor sees them.
class SignalFd {
 public:
  SignalFd() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGTERM);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGHUP);
    ::pthread_sigmask(SIG_BLOCK, &set_, &old_);
    fd_ = ::signalfd(-1, &set_, SFD_NONBLOCK | SFD_CLOEXEC);
    if (fd_ < 0) throw std::runtime_error("signalfd failed");
  }
  ~SignalFd() {
    ::close(fd_);
    ::pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  int fd() const { return fd_; }
  /// The signal number waiting, or 0.
  int take() const {
    signalfd_siginfo info{};
    return ::read(fd_, &info, sizeof info) == static_cast<ssize_t>(sizeof info) ? static_cast<int>(info.ssi_signo) : 0;
  }

 private:
  sigset_t set_{};
  sigset_t old_{};
  int fd_ = -1;
};

/// What `liod run`'s main loop does besides waiting for a signal, once per pass (100 ms): the
/// PPS correction, host clock steps, systemd's watchdog and status, the health line in the log.
class Supervisor {
 public:
  Supervisor(const Config& config, Pipeline& pipeline, std::unique_ptr<drivers::PpsDiscipline> pps)
      : config_(config), pipeline_(pipeline), pps_(std::move(pps)),
        jumps_(static_cast<std::int64_t>(config.time.jump_threshold_s * 1e9)) {
    std::uint64_t watchdog_us = 0;
    watchdog_ = ::sd_watchdog_enabled(0, &watchdog_us) > 0 && watchdog_us > 0;
    ping_every_ = std::chrono::microseconds(watchdog_ ? watchdog_us / 2 : 1000000);
    next_ping_ = next_stall_log_ = Clock::now();
    next_health_ = Clock::now() + health_every();
  }

  void tick() {
    if (pps_) pipeline_.imu_output().pps_correction_ns.store(pps_->correction_ns());
    if (const auto step = jumps_.check(); step != 0) {
      spdlog::warn("host clock jumped by {:.3f} s (CLOCK_REALTIME step); host-stamped times are kept continuous, poses "
                   "flagged clock_jump for {} s",
                   static_cast<double>(step) * 1e-9, config_.time.jump_flag_s);
      pipeline_.note_host_clock_jump();
    }
    const auto now = Clock::now();
    if (now >= next_ping_) watchdog(now);
    if (config_.pose_socket.health_log_interval_s > 0 && now >= next_health_) {
      next_health_ = now + health_every();
      spdlog::info("health {}", pipeline_.health_json(rates_));
      const std::string status = "STATUS=sweeps " + std::to_string(pipeline_.lidar_output().sweeps()) + ", IMU samples " +
                                 std::to_string(pipeline_.imu_output().samples());
      ::sd_notify(0, status.c_str());
    }
  }

 private:
  using Clock = std::chrono::steady_clock;
  // A thread is stalled when it has not passed its loop for this long: every driver and worker
  // loop waits at most 100 ms, and a scan takes tens of ms, so 2 s means stuck. The backend's
  // one unit of work may take longer (threads.backend_work_limit_s, heartbeat.hpp).
  static constexpr std::chrono::milliseconds kStallLimit{2000};

  Clock::duration health_every() const {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.pose_socket.health_log_interval_s));
  }

  void watchdog(Clock::time_point now) {
    const auto stalled = pipeline_.stalled(kStallLimit);
    if (stalled.empty()) {
      if (watchdog_) ::sd_notify(0, "WATCHDOG=1");
      if (withheld_) spdlog::info("all threads progressing again; watchdog pings resumed");
      withheld_ = false;
      next_ping_ = now + ping_every_;
      return;
    }
    // No ping: systemd's watchdog restarts us if this persists for WatchdogSec. Checked again
    // at the next pass, so that the ping resumes the moment the thread does.
    if (!withheld_ || now >= next_stall_log_) {
      std::string names;
      for (const auto& s : stalled) names += (names.empty() ? "" : ", ") + s;
      spdlog::error("threads not progressing: {}; withholding the watchdog ping", names);
      next_stall_log_ = now + ping_every_;
    }
    withheld_ = true;
  }

  const Config& config_;
  Pipeline& pipeline_;
  std::unique_ptr<drivers::PpsDiscipline> pps_;
  drivers::ClockJumpDetector jumps_;
  bool watchdog_ = false;
  bool withheld_ = false;
  Clock::duration ping_every_{};
  Clock::time_point next_ping_, next_stall_log_, next_health_;
  HealthRates rates_;
};

std::unique_ptr<drivers::PpsDiscipline> open_pps(const Config& config) {
  if (config.time.pps_chip.empty()) return nullptr;
  try {
    return std::make_unique<drivers::PpsDiscipline>(config.time.pps_chip, config.time.pps_line);
  } catch (const std::exception& e) {
    spdlog::warn("{}; IMU stamps stay on the host clock", e.what());
    return nullptr;
  }
}

bool has_cap_ipc_lock() {
  __user_cap_header_struct header{_LINUX_CAPABILITY_VERSION_3, 0};
  __user_cap_data_struct data[2]{};
  if (::syscall(SYS_capget, &header, data) != 0) return false;
  return (data[CAP_IPC_LOCK / 32].effective & (1U << (CAP_IPC_LOCK % 32))) != 0;
}

// A page fault on a real-time thread's path (a stack or heap page touched for the first time, a
// page reclaimed under memory pressure) stalls the thread for as long as the kernel takes to
// supply it; mlockall keeps every page resident. With MCL_FUTURE each later mapping is locked
// too and counted against RLIMIT_MEMLOCK: under a finite limit without CAP_IPC_LOCK an allocation
// past it would fail (mmap EAGAIN), so memory is locked only where the limit is unlimited (the
// unit's LimitMEMLOCK=infinity) or CAP_IPC_LOCK lifts it. Anything else is a warning: liod runs
// on with pageable memory.
void lock_memory(const ThreadsConfig& threads) {
  if (!threads.lock_memory) {
    spdlog::info("memory not locked (threads.lock_memory: false)");
    return;
  }
  rlimit limit{};
  ::getrlimit(RLIMIT_MEMLOCK, &limit);
  if (limit.rlim_cur != RLIM_INFINITY && !has_cap_ipc_lock()) {
    spdlog::warn("memory not locked: RLIMIT_MEMLOCK is {} KiB and no CAP_IPC_LOCK (the unit's LimitMEMLOCK=infinity "
                 "lifts it); page faults may stall the real-time threads",
                 limit.rlim_cur / 1024);
    return;
  }
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    const int error = errno;
    spdlog::warn("mlockall failed: {}; memory not locked, page faults may stall the real-time threads",
                 std::strerror(error));
    return;
  }
  spdlog::info("memory locked (mlockall MCL_CURRENT | MCL_FUTURE)");
}

/// Waits for SIGTERM/SIGINT, a thread's error or the time limit; returns the exit code so far.
int supervise(const SignalFd& signals, Pipeline& pipeline, Supervisor& supervisor, double max_seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                               std::chrono::duration<double>(max_seconds));
  for (;;) {
    pollfd p{signals.fd(), POLLIN, 0};
    ::poll(&p, 1, 100);
    if ((p.revents & POLLIN) != 0) {
      const int sig = signals.take();
      if (sig == SIGHUP) {
        spdlog::info("SIGHUP: configuration reload is not supported; restart the service to apply changes");
        continue;
      }
      spdlog::info("signal {}: stopping", sig);
      return 0;
    }
    if (!pipeline.error().empty()) return 1;
    if (max_seconds > 0 && std::chrono::steady_clock::now() >= deadline) return 0;
    supervisor.tick();
  }
}

}  // namespace

int run_daemon(const Config& config, const RunOptions& options) {
  lock_memory(config.threads);
  SignalFd signals;
  std::unique_ptr<Recorder> recorder;
  if (!options.record_dir.empty()) {
    std::filesystem::create_directories(options.record_dir);
    recorder = std::make_unique<Recorder>(options.record_dir);
  }
  const auto socket_dir = std::filesystem::path(config.output.pose_socket).parent_path();
  if (!socket_dir.empty() && !std::filesystem::is_directory(socket_dir)) {
    throw std::runtime_error("pose socket directory " + socket_dir.string() +
                             " does not exist (systemd's RuntimeDirectory= creates /run/liod)");
  }
  PipelineOptions po;
  po.ordering = Ordering::Arrival;
  po.imu_rate_poses = config.pose_socket.imu_rate;
  po.pose_socket = config.output.pose_socket;
  po.bridge_clock_steps = true;
  if (config.viewer.foxglove_port > 0) {
    po.viewer = std::make_shared<FoxgloveServer>(config.viewer, config.extrinsics, static_cast<std::uint16_t>(config.viewer.foxglove_port));
  }
  Pipeline pipeline(config, po);
  if (recorder) {
    Recorder* r = recorder.get();
    pipeline.lidar_output().tap = [r](std::span<const std::uint8_t> p, std::int64_t t, std::uint16_t port) { r->packet(p, t, port); };
    pipeline.imu_output().tap = [r](const ImuSample& s) { r->sample(s); };
  }
  Supervisor supervisor(config, pipeline, open_pps(config));
  auto lidar = make_live_lidar_source(config);
  auto imu = make_live_imu_source(config);
  spdlog::info("liod: LiDAR {}, IMU {}, poses on {}", lidar->describe(), imu ? imu->describe() : "none",
               config.output.pose_socket);
  pipeline.start(std::move(lidar), std::move(imu));
  ::sd_notify(0, "READY=1\nSTATUS=running");
  int exit_code = supervise(signals, pipeline, supervisor, options.max_seconds);
  ::sd_notify(0, "STOPPING=1");
  // Drain what the rings hold (bounded), then flush recordings: a stop loses no received data.
  const bool clean = pipeline.drain(std::chrono::milliseconds(3000));
  if (!clean) spdlog::warn("some threads did not drain within 3 s; stopped them");
  const bool recording_complete = !recorder || recorder->finish();
  if (!pipeline.error().empty() || !recording_complete) exit_code = 1;
  spdlog::info("liod stopped ({} scans with a pose, {} keyframes to the backend)", pipeline.totals().processed,
               pipeline.keyframes_received());
  return exit_code;
}

namespace {

// The CSV columns of `liod pose --format csv`; sd_*: square roots of the covariance's diagonal.
constexpr const char* kPoseCsvHeader =
    "type,seq,time,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz,sd_x,sd_y,sd_z,sd_roll,sd_pitch,sd_yaw,flags,status,"
    "map_seq,map_x,map_y,map_z,map_qx,map_qy,map_qz,map_qw\n";

double pose_sd(const pose::PoseMessage& p, int i) { return std::sqrt(std::max(0.0, p.covariance(i, i))); }

// One pose as `format` prints it (not Json: those lines are the server's).
std::string format_pose(const pose::PoseMessage& p, PoseFormat format, bool map_frame) {
  const char* type = p.type == pose::MessageType::ScanPose ? "scan" : "imu";
  const auto& q = p.orientation;
  const auto& mq = p.map_orientation;
  char line[1536];
  if (format == PoseFormat::Tum) {
    // The precision of `liod replay --trajectory` (trajectory_writer.cpp), so the files compare.
    const Eigen::Vector3d& t = map_frame ? p.map_position : p.position;
    const Eigen::Quaterniond& r = map_frame ? mq : q;
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", p.time, t.x(), t.y(), t.z(), r.x(),
                  r.y(), r.z(), r.w());
  } else if (format == PoseFormat::Csv) {
    // %.17g: the exact double, for a log that is analysed later.
    std::snprintf(line, sizeof line,
                  "%s,%" PRIu32 ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                  "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%" PRIu32 ",%s,%" PRIu32 ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                  type, p.sequence, p.time, p.position.x(), p.position.y(), p.position.z(), q.x(), q.y(), q.z(), q.w(),
                  p.velocity.x(), p.velocity.y(), p.velocity.z(), p.angular_rate.x(), p.angular_rate.y(), p.angular_rate.z(),
                  pose_sd(p, 0), pose_sd(p, 1), pose_sd(p, 2), pose_sd(p, 3), pose_sd(p, 4), pose_sd(p, 5), p.flags, pose::flag_names(p.flags).c_str(),
                  p.correction_sequence, p.map_position.x(), p.map_position.y(), p.map_position.z(), mq.x(), mq.y(), mq.z(),
                  mq.w());
  } else {
    std::snprintf(line, sizeof line,
                  "%-4s %.6f p %.3f %.3f %.3f q %.5f %.5f %.5f %.5f v %.3f %.3f %.3f w %.4f %.4f %.4f sd_xyz %.3f %.3f %.3f %s "
                  "map %.3f %.3f %.3f #%" PRIu32 "\n",
                  type, p.time, p.position.x(), p.position.y(), p.position.z(), q.x(), q.y(), q.z(), q.w(), p.velocity.x(),
                  p.velocity.y(), p.velocity.z(), p.angular_rate.x(), p.angular_rate.y(), p.angular_rate.z(), pose_sd(p, 0), pose_sd(p, 1),
                  pose_sd(p, 2), pose::flag_names(p.flags).c_str(), p.map_position.x(), p.map_position.y(), p.map_position.z(),
                  p.correction_sequence);
  }
  return line;
}

// JSON format: the server's text lines as they come; false when the stream ended.
bool print_json_line(PoseClient& client, const PoseCommandOptions& o, std::chrono::milliseconds timeout, std::ostream& out,
                     long& poses) {
  std::string l;
  if (!client.read_line(l, timeout)) return false;
  const bool is_health = l.rfind("{\"type\":\"health\"", 0) == 0;
  if (is_health && !o.health) return true;
  out << l << '\n' << std::flush;
  if (!is_health) ++poses;
  return true;
}

// The binary formats: one decoded message; false when the stream ended.
bool print_message(PoseClient& client, const PoseCommandOptions& o, std::chrono::milliseconds timeout, std::ostream& out,
                   long& poses) {
  pose::Message m;
  if (!client.read(m, timeout)) return false;
  if (m.type == pose::MessageType::Health) {
    // A TUM or CSV file holds poses only.
    if (o.health && o.format == PoseFormat::Text) out << "health " << m.health << '\n' << std::flush;
    return true;
  }
  out << format_pose(m.pose, o.format, o.map_frame) << std::flush;
  ++poses;
  return true;
}

}  // namespace

int run_pose_client(const PoseCommandOptions& o, std::ostream& out) {
  PoseClient client(o.socket);
  if (o.format == PoseFormat::Json) client.request("json");
  if (o.scan_only || o.format == PoseFormat::Tum) client.request("scan");
  if (o.format == PoseFormat::Csv) out << kPoseCsvHeader;
  const auto timeout = std::chrono::milliseconds(static_cast<long>(o.timeout_s * 1000));
  long poses = 0;
  while (o.count == 0 || poses < o.count) {
    const bool more = o.format == PoseFormat::Json ? print_json_line(client, o, timeout, out, poses)
                                                   : print_message(client, o, timeout, out, poses);
    if (!more) break;
  }
  if (!client.connected()) return poses > 0 ? 0 : 1;
  return 0;
}

}  // namespace liod
