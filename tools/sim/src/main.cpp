// liod-sim: writes a simulated RS-Helios + IMU drive with ground truth (see tools/sim/README.md).

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "liod/sim/simulator.hpp"

#ifndef LIOD_SHARED_DIR
#define LIOD_SHARED_DIR "../shared"
#endif

int main(int argc, char** argv) {
  using liod::sim::SimConfig;
  CLI::App app{"liod-sim: simulated RS-Helios-5515 (or HDL-64E in KITTI raw's layout) + IMU drive with ground truth"};
  std::string route = "urban";
  SimConfig cfg;
  cfg.angles_csv = std::string(LIOD_SHARED_DIR) + "/data/robosense/helios32_angles.csv";
  bool rolling = false;
  bool stationary = false;
  bool no_noise = false;
  bool no_ego = false;
  bool quiet = false;
  app.add_option("--route", route, "urban, loop, figure8, highway or tunnel")->required();
  app.add_option("--seed", cfg.scene.seed, "scenario seed (same seed -> same bytes)")->required();
  app.add_option("--duration", cfg.scene.duration, "seconds of driving")->required();
  app.add_option("--max-speed", cfg.scene.max_speed, "m/s")->default_val(12.0);
  app.add_option("--out", cfg.out_dir, "existing output directory")->required();
  app.add_flag("--rolling-start", rolling, "already moving at t = 0 (default for urban, highway)");
  app.add_flag("--static-start", stationary, "stand still first (default for loop, figure8, tunnel)");
  app.add_option("--static-seconds", cfg.scene.static_seconds, "rest before moving off with --static-start")
      ->default_val(3.0);
  auto* imu_rate_option = app.add_option("--imu-rate", cfg.imu_rate, "IMU samples per second")->default_val(200.0);
  std::string lidar = "helios";
  app.add_option("--lidar", lidar, "helios (RS-Helios-5515 packets, lidar.pcap) or hdl64e (KITTI raw layout, 100 Hz OXTS)");
  app.add_option("--kitti-raw", cfg.kitti_dir, "with --lidar hdl64e: existing folder for KITTI raw's layout (default: --out)");
  app.add_flag("--no-noise", no_noise, "exact IMU and LiDAR ranges (detection dropouts remain)");
  app.add_option("--angle-error-deg", cfg.angle_error_deg,
                 "largest difference between the LiDAR's true and published beam angles, per channel")
      ->default_val(0.005);
  app.add_flag("--dual-return", cfg.dual_return, "dual-return packets (strongest + last)");
  app.add_flag("--no-ego", no_ego, "do not let the LiDAR see its own car");
  app.add_option("--angles", cfg.angles_csv, "Helios-32 angle table (vert_deg,horiz_deg per channel)");
  app.add_option("--threads", cfg.threads, "worker threads (output does not depend on it)")->default_val(2);
  app.add_option("--epoch", cfg.epoch_s, "UTC seconds of t = 0 on the IMU clock")->default_val(1700000000);
  app.add_flag("--quiet", quiet, "no progress output");
  std::uint64_t route_seed = 0;
  auto* route_seed_option = app.add_option("--route-seed", route_seed,
                                           "urban, loop: another route through the seed's world (same duration and max "
                                           "speed), from a random street and heading");
  std::vector<double> rpy_deg;
  std::vector<double> translation_m;
  double time_offset_s = 0.0;
  app.add_option("--extrinsic-rotation-deg", rpy_deg, "true LiDAR-to-IMU rotation r,p,y in degrees (R = Rz Ry Rx), instead of the seed's")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--extrinsic-translation-m", translation_m, "true LiDAR-to-IMU translation x,y,z in m, instead of the seed's")
      ->delimiter(',')
      ->expected(3);
  auto* offset_option =
      app.add_option("--time-offset-s", time_offset_s, "true LiDAR clock offset (t_imu = t_lidar + offset), instead of the seed's");
  // The road as hard as a real one (README "Hard roads"): each condition alone, or all with --hard.
  bool hard = false;
  std::string imu_grade = "default";
  liod::sim::RoadConditions road;
  app.add_flag("--hard", hard, "every condition below at the levels of issue 56 (options given as well override)");
  app.add_flag("--traffic", road.traffic, "vehicles driving the other lanes and ahead (urban, loop, highway, tunnel)");
  app.add_flag("--wind", road.wind, "tree crowns, bushes and hedges sway in the wind");
  app.add_flag("--open-stretch", road.open_stretch, "~100 m of the route with only ground and a hedge");
  auto* vib_option = app.add_option("--vibration-scale", road.vibration_scale,
                                    "road vibration (1: body bounce 3 Hz, wheel hop 11 Hz, pitch shake 9 Hz), 0 = none");
  auto* grade_option = app.add_option("--imu-grade", imu_grade, "default, or consumer (a Bosch BMI088)");
  auto* dropout_option = app.add_option("--dropout", road.dropout, "fraction of returns dropped at random");
  auto* rain_option = app.add_option("--rain", road.rain_rate, "spurious near returns (rain drops) per second");
  CLI11_PARSE(app, argc, argv);
  if (hard) {
    const liod::sim::RoadConditions given = road;
    road = liod::sim::RoadConditions::hard();
    if (*vib_option) road.vibration_scale = given.vibration_scale;
    if (*dropout_option) road.dropout = given.dropout;
    if (*rain_option) road.rain_rate = given.rain_rate;
  }
  if (*grade_option || !hard) {
    if (imu_grade != "default" && imu_grade != "consumer") {
      std::fprintf(stderr, "liod-sim: --imu-grade takes default or consumer, got '%s'\n", imu_grade.c_str());
      return 2;
    }
    road.consumer_imu = imu_grade == "consumer";
  }
  if (!(road.vibration_scale >= 0.0) || road.vibration_scale > 5.0 || !(road.dropout >= 0.0) || road.dropout > 0.9 ||
      !(road.rain_rate >= 0.0) || road.rain_rate > 100000.0) {
    std::fprintf(stderr, "liod-sim: --vibration-scale takes [0, 5], --dropout [0, 0.9], --rain [0, 100000] per second\n");
    return 2;
  }
  cfg.conditions = road;
  if (lidar != "helios" && lidar != "hdl64e") {
    std::fprintf(stderr, "liod-sim: --lidar takes helios or hdl64e, got '%s'\n", lidar.c_str());
    return 2;
  }
  if (lidar == "hdl64e") {
    // KITTI's OXTS extract is 100 Hz; imu.csv beside it holds the same samples.
    if (*imu_rate_option && cfg.imu_rate != 100.0) {
      std::fprintf(stderr, "liod-sim: --lidar hdl64e writes the 100 Hz OXTS extract: --imu-rate must be 100\n");
      return 2;
    }
    if (cfg.dual_return || road.traffic || road.dropout > 0.0 || road.rain_rate > 0.0) {
      std::fprintf(stderr, "liod-sim: --lidar hdl64e takes no --dual-return, --traffic, --dropout or --rain\n");
      return 2;
    }
    cfg.imu_rate = 100.0;
    cfg.lidar = liod::sim::LidarKind::Hdl64e;
  } else if (!cfg.kitti_dir.empty()) {
    std::fprintf(stderr, "liod-sim: --kitti-raw needs --lidar hdl64e\n");
    return 2;
  }
  if (!cfg.kitti_dir.empty() && !std::filesystem::is_directory(cfg.kitti_dir)) {
    std::fprintf(stderr, "liod-sim: --kitti-raw folder '%s' does not exist\n", cfg.kitti_dir.c_str());
    return 2;
  }
  if (route_seed_option->count() > 0) cfg.scene.route_seed = route_seed;

  const auto kind = liod::sim::parse_route(route);
  if (!kind) {
    std::fprintf(stderr, "liod-sim: unknown route '%s' (use urban, loop, figure8, highway, tunnel)\n",
                 route.c_str());
    return 2;
  }
  if (!(cfg.scene.duration > 0.0) || cfg.scene.duration > 3600.0) {
    std::fprintf(stderr, "liod-sim: --duration must be in (0, 3600] seconds, got %g\n", cfg.scene.duration);
    return 2;
  }
  if (!(cfg.scene.max_speed >= 1.0) || cfg.scene.max_speed > 45.0) {
    std::fprintf(stderr, "liod-sim: --max-speed must be in [1, 45] m/s, got %g\n", cfg.scene.max_speed);
    return 2;
  }
  if (!(cfg.imu_rate >= 50.0) || cfg.imu_rate > 2000.0) {
    std::fprintf(stderr, "liod-sim: --imu-rate must be in [50, 2000] Hz, got %g\n", cfg.imu_rate);
    return 2;
  }
  if (!(cfg.angle_error_deg >= 0.0) || cfg.angle_error_deg > 0.1) {
    std::fprintf(stderr, "liod-sim: --angle-error-deg must be in [0, 0.1] degrees, got %g\n", cfg.angle_error_deg);
    return 2;
  }
  if (cfg.scene.route_seed && *kind != liod::sim::RouteKind::Urban && *kind != liod::sim::RouteKind::Loop) {
    std::fprintf(stderr, "liod-sim: --route-seed needs a city route (urban, loop)\n");
    return 2;
  }
  if (road.traffic && *kind == liod::sim::RouteKind::Figure8) {
    std::fprintf(stderr, "liod-sim: --traffic needs a route with lanes (urban, loop, highway, tunnel)\n");
    return 2;
  }
  if (rolling && stationary) {
    std::fprintf(stderr, "liod-sim: --rolling-start and --static-start exclude each other\n");
    return 2;
  }
  if (cfg.threads < 1 || cfg.threads > 64) {
    std::fprintf(stderr, "liod-sim: --threads must be in [1, 64]\n");
    return 2;
  }
  if (!std::filesystem::is_directory(cfg.out_dir)) {
    std::fprintf(stderr, "liod-sim: output directory '%s' does not exist\n", cfg.out_dir.c_str());
    return 2;
  }
  if (!rpy_deg.empty()) {
    if (rpy_deg.size() != 3 || std::abs(rpy_deg[0]) > 180.0 || std::abs(rpy_deg[1]) > 90.0 || std::abs(rpy_deg[2]) > 180.0) {
      std::fprintf(stderr, "liod-sim: --extrinsic-rotation-deg takes r,p,y with |r|, |y| <= 180 and |p| <= 90\n");
      return 2;
    }
    cfg.extrinsic_rpy_deg = Eigen::Vector3d(rpy_deg[0], rpy_deg[1], rpy_deg[2]);
  }
  if (!translation_m.empty()) {
    if (translation_m.size() != 3 || std::abs(translation_m[0]) > 5.0 || std::abs(translation_m[1]) > 5.0 ||
        std::abs(translation_m[2]) > 5.0) {
      std::fprintf(stderr, "liod-sim: --extrinsic-translation-m takes x,y,z within 5 m of the IMU\n");
      return 2;
    }
    cfg.extrinsic_translation_m = Eigen::Vector3d(translation_m[0], translation_m[1], translation_m[2]);
  }
  if (*offset_option) {
    // The true trajectory starts 30 ms before t = 0, where the first firing of a LiDAR clock
    // ahead of the IMU's falls.
    if (!(time_offset_s >= -0.025) || time_offset_s > 0.5) {
      std::fprintf(stderr, "liod-sim: --time-offset-s must be in [-0.025, 0.5] s, got %g\n", time_offset_s);
      return 2;
    }
    cfg.time_offset_s = time_offset_s;
  }
  cfg.scene.route = *kind;
  cfg.scene.start = rolling ? liod::sim::StartMode::Rolling
                            : (stationary ? liod::sim::StartMode::Static : liod::sim::StartMode::Default);
  cfg.noise = !no_noise;
  cfg.ego_body = !no_ego;

  try {
    const auto t0 = std::chrono::steady_clock::now();
    const liod::sim::Simulation sim(cfg);
    const auto t1 = std::chrono::steady_clock::now();
    int shown = -1;
    const auto report = sim.write_all([&](double f) {
      const int pct = static_cast<int>(f * 100.0);
      if (!quiet && pct / 10 != shown / 10) {
        shown = pct;
        std::fprintf(stderr, "\rliod-sim: %3d %%", pct);
      }
    });
    const auto t2 = std::chrono::steady_clock::now();
    if (!quiet && cfg.lidar == liod::sim::LidarKind::Hdl64e) {
      std::fprintf(stderr,
                   "\rliod-sim: %s seed %llu, %.1f s, %.0f m driven: %llu HDL-64E sweeps, %.1f M returns of %.1f M rays, "
                   "%llu OXTS samples in %s\n",
                   route.c_str(), static_cast<unsigned long long>(cfg.scene.seed), cfg.scene.duration,
                   sim.drive_stats().distance, static_cast<unsigned long long>(report.sweeps),
                   static_cast<double>(report.returns) * 1e-6, static_cast<double>(report.rays) * 1e-6,
                   static_cast<unsigned long long>(report.imu_samples), liod::sim::kitti_raw_drive(cfg).c_str());
    } else if (!quiet) {
      const double build = std::chrono::duration<double>(t1 - t0).count();
      const double run = std::chrono::duration<double>(t2 - t1).count();
      std::fprintf(stderr,
                   "\rliod-sim: %s seed %llu, %.1f s, %.0f m driven: %llu MSOP + %llu DIFOP packets, "
                   "%.1f M returns of %.1f M rays, %llu IMU samples; world %.1f s, sensors %.1f s\n",
                   route.c_str(), static_cast<unsigned long long>(cfg.scene.seed), cfg.scene.duration,
                   sim.drive_stats().distance, static_cast<unsigned long long>(report.msop_packets),
                   static_cast<unsigned long long>(report.difop_packets),
                   static_cast<double>(report.returns) * 1e-6, static_cast<double>(report.rays) * 1e-6,
                   static_cast<unsigned long long>(report.imu_samples), build, run);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "liod-sim: %s\n", e.what());
    return 1;
  }
  return 0;
}
