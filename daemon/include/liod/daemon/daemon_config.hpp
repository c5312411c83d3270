#pragma once
// The daemon's configuration: logging, outputs, threads and the pose socket (config/liod.yaml
// explains each key).

#include <string>

namespace liod {

struct LogConfig {
  std::string level = "info";  // trace, debug, info, warn, error, off
};

struct OutputConfig {
  std::string pose_socket = "/run/liod/pose.sock";
  std::string state_dir = "/var/lib/liod";
};

struct ThreadConfig {
  int priority = 0;  // 0 = normal scheduling; 1..99 = SCHED_FIFO priority (within RLIMIT_RTPRIO, or CAP_SYS_NICE)
  int cpu = -1;      // -1 = any CPU; else pin to this CPU
};

struct ThreadsConfig {
  ThreadConfig lidar{70, -1};
  ThreadConfig imu{75, -1};
  ThreadConfig odometry{60, -1};
  ThreadConfig publisher{65, -1};
  int backend_nice = 10;            // the backend runs SCHED_OTHER at this nice value
  int scan_ring = 8;                // ring sizes (rounded up to powers of two)
  int imu_ring = 4096;
  int pose_ring = 4096;
  int keyframe_ring = 64;
  double backend_max_lag_s = 5.0;      // live: a keyframe that waited longer for the backend is skipped (no loop check)
  double backend_work_limit_s = 60.0;  // one keyframe's backend work running longer than this is a stall (watchdog)
  // Live: a scan whose data (sweep, and IMU up to its end) has waited longer than this for the
  // odometry, and that is older than pose_socket.stale_after_s, is skipped when a newer scan is
  // there: the odometry goes on with the newest (counted). One scan period at 10 Hz.
  double scan_max_lag_s = 0.1;
  // `liod run` / `liod record`: mlockall(MCL_CURRENT | MCL_FUTURE) at start, so that no page fault
  // to disk stalls a real-time thread (needs LimitMEMLOCK=infinity or CAP_IPC_LOCK; else a warning).
  bool lock_memory = true;
};

struct PoseSocketConfig {
  std::string mode = "0660";        // permissions of the socket file (octal)
  int max_clients = 32;
  int client_buffer_bytes = 262144; // a client further behind than this skips messages
  double stuck_timeout_s = 2.0;     // a client that accepts nothing for this long is disconnected
  bool imu_rate = true;             // also publish IMU-rate poses
  double imu_rate_horizon_s = 1.0;  // no IMU-rate pose more than this after the last scan update (data time)
  double health_interval_s = 1.0;   // health message period on the socket
  double health_log_interval_s = 10.0;  // health line period in the log
  double max_speed_mps = 100.0;     // a faster state is implausible, not ok
  double max_gyro_bias_rad_s = 0.1; // a larger gyro bias (any axis) is implausible, not ok
  double max_accel_bias_m_s2 = 1.0; // a larger accelerometer bias (any axis) is implausible, not ok
  double stale_after_s = 0.3;       // live: a pose published later than this after its input arrived is stale, not ok
};

/// The live view: a Foxglove WebSocket server (foxglove_server.hpp) for Foxglove Studio.
struct ViewerConfig {
  int foxglove_port = 0;                  // 0 = off; else the TCP port (Foxglove's default: 8765)
  std::string bind_address = "127.0.0.1"; // IPv4/IPv6 address to listen on (0.0.0.0: every interface)
  int max_clients = 8;                    // further connections are refused
  int client_queue_bytes = 8 << 20;       // a client further behind than this loses its oldest messages
  double map_interval_s = 1.0;            // the local map and the trajectories at most this often
  double map_voxel_m = 0.5;               // the local map's downsampling (one point per voxel)
  double scan_voxel_m = 0.2;              // the scan's downsampling; 0 = every point
};

/// Everything the daemon's own parts need.
struct DaemonConfig {
  LogConfig log;
  OutputConfig output;
  ThreadsConfig threads;
  PoseSocketConfig pose_socket;
  ViewerConfig viewer;
};

}  // namespace liod
