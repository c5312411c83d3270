#pragma once
// The drive every fault test starts from: `liod-sim --route urban --seed 1 --duration 25
// --max-speed 12` (rolling start, ~220 m with a 90 deg turn at 13-15 s), and the start-up drives.
// Each is generated once into the build tree (test-data/<name>/) and shared by the test processes
// (tests/support/simulated_drive.hpp).

#include <filesystem>

#include "liod/eval/trajectory.hpp"
#include "liod/fault/recording.hpp"
#include "test_env.hpp"

namespace liod::test {

struct FaultDrive {
  std::filesystem::path dir;  ///< lidar.pcap, imu.csv, groundtruth.tum, extrinsics.yaml
  fault::Recording recording;
  eval::Trajectory truth;
  /// Absolute time (s, IMU clock) of a fault time (s after the recording's origin).
  [[nodiscard]] double at(double seconds) const { return static_cast<double>(recording.origin_ns) * 1e-9 + seconds; }
  [[nodiscard]] double end() const { return truth.stamps.back(); }
};

/// The drive, or null when liod-sim is not built in this tree or failed.
const FaultDrive* fault_drive();

/// `liod-sim --route highway --seed 2 --duration 8 --max-speed 12`: a rolling start at 12 m/s
/// between guardrails, with few posts in sight (made like the fault drive, in test-data/rails-drive/).
const FaultDrive* rails_drive();

/// `liod-sim --route highway --seed 4 --duration 12 --max-speed 12`: a rolling start at 12 m/s
/// where the guard rail's posts, 4 m apart, are seen only where a ring passes below the rail
/// (made like the fault drive, in test-data/posts-drive/).
const FaultDrive* posts_drive();

/// `liod-sim --route highway --seed 1 --duration 12 --max-speed 12 --static-start`: 3 s at rest
/// between guard rails, then off (made like the fault drive, in test-data/rest-drive/).
const FaultDrive* rest_drive();

/// `liod-sim --route tunnel --seed 1 --duration 25 --max-speed 15`: 3 s at rest on the approach
/// to a tunnel, then off and into it (made like the fault drive, in test-data/tunnel-rest-drive/).
const FaultDrive* tunnel_rest_drive();
/// Highway seed 4, 8 s up to 15 m/s, 3 s at rest: moving off between slanted barrier faces.
const FaultDrive* move_off_drive();
/// `liod-sim --route tunnel --seed 9 --duration 25 --max-speed 15`: 3 s at rest inside a tunnel of
/// constant section, then off at 1.6 m/s^2 to 15 m/s.
const FaultDrive* tunnel_move_off_drive();

/// `liod-sim --route highway --seed 8 --duration 50 --max-speed 15 --no-noise --angle-error-deg 0`:
/// a rolling start at 15 m/s under gantries (23-27 s, 41-45 s) between long stretches of rails.
const FaultDrive* gantries_drive();

/// `liod-sim --route tunnel --seed 10 --duration 40 --max-speed 15 --no-noise --angle-error-deg 0`: 3 s at
/// rest inside a tunnel, then off at 1.6 m/s^2 (a noise-free IMU: its gyro bias is zero).
const FaultDrive* tunnel_heading_drive();

/// `liod-sim --route highway --seed 108 --duration 6 --max-speed 15`: a rolling start at 15 m/s
/// whose first two scans alone overlap best at 2-3 m/s (speed_search).
const FaultDrive* aliasing_posts_drive();

/// `liod-sim --route highway --seed 9 --duration 8 --max-speed 15`: a rolling start at 15 m/s past
/// posts 4 m apart, whose rails-free evidence briefly leads at their alias, -5 m/s (each scan's
/// posts on the next ones' places two scans before).
const FaultDrive* backward_alias_drive();

/// `liod-sim --route highway --seed 53 --duration 6 --max-speed 15`: a rolling start at 15 m/s
/// whose rails-free evidence is first highest at 50 m/s, the search's end, still rising.
const FaultDrive* grid_edge_alias_drive();

/// `liod-sim --route highway --seed 131 --duration 8 --max-speed 13`: a rolling start at 13 m/s
/// whose rings cut the right rail's faces in spots fixed in the sensor's frame, so that even off
/// the rails the first 2 s score a standstill best (speed_search).
const FaultDrive* rail_faces_drive();

/// `liod-sim --route highway --seed 7 --duration 12 --max-speed 12`: a rolling start at 12 m/s
/// past a car parked on the shoulder (made like the fault drive, in test-data/parked-car-drive/).
const FaultDrive* parked_car_drive();

/// `liod-sim --route highway --seed 7 --duration 60 --max-speed 15`: a rolling start at 15 m/s over
/// a crest (the body pitching at 0.009 rad/s for its first seconds), whose speed search runs to its
/// 2 s limit.
const FaultDrive* crest_start_drive();

/// `liod-sim --route tunnel --seed 7 --duration 40 --max-speed 15`: a static start inside the
/// tunnel whose moving off turned the heading.
const FaultDrive* tunnel_yaw_bias_drive();

/// `liod-sim --route urban --seed 1 --duration 60 --max-speed 12`: the fault drive's route, long
/// enough for a LiDAR that reboots (30 s) and comes back.
const FaultDrive* reboot_drive();

}  // namespace liod::test

// The drive as `var`: skips without liod-sim or ../shared (fails under CI, see test_env.hpp), fails
// when liod-sim does not make it.
#define LIOD_REQUIRE_DRIVE(var, drive)                                                         \
  LIOD_REQUIRE_SIM();                                                                          \
  const auto* var = liod::test::drive();                                                       \
  ASSERT_NE(var, nullptr) << "liod-sim failed to make the drive: see " << (liod::test::drive_tree() / "test-data/*/sim.log")
#define LIOD_REQUIRE_FAULT_DRIVE(var) LIOD_REQUIRE_DRIVE(var, fault_drive)
