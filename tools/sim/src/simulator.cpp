#include "liod/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <vector>

#include "liod/sim/angles.hpp"
#include "liod/sim/helios_packet.hpp"
#include "liod/sim/pcap_writer.hpp"

namespace liod::sim {

namespace {
constexpr std::uint64_t kMountStream = 0x6D6F756E74ULL;
constexpr std::uint64_t kLidarStream = 0x6C69646172ULL;
constexpr std::uint64_t kNetStream = 0x6E6574ULL;

/// Microseconds of LiDAR-clock time at the start of firing g (g * 55.5556 us), exactly.
std::uint64_t firing_time_us(std::uint64_t g) { return g * 500U / 9U; }
}  // namespace

Simulation::Simulation(SimConfig config) : config_(std::move(config)) {
  const SceneRequest& req = config_.scene;
  if (!(req.duration > 0.0) || !(req.max_speed > 0.0) || !(config_.imu_rate > 0.0)) {
    throw std::invalid_argument("duration, max speed and IMU rate must be positive");
  }
  scene_ = generate_scene(req);
  vehicle_.roughness = scene_.road_roughness;
  const RoadConditions& hard = config_.conditions;
  vehicle_.road_vibration = hard.vibration_scale;
  const PathCurve path(scene_.plan.points, 2.5);
  trajectory_ = std::make_unique<Trajectory>(
      generate_drive(scene_.plan, path, scene_.world.terrain, vehicle_, req.duration, req.seed, &stats_));
  // The added conditions draw from streams of their own, after everything else.
  if (hard.open_stretch) {
    open_stretch_ = clear_open_stretch(scene_, *trajectory_, req.duration, req.seed);
  }
  if (hard.wind) {
    scene_.world.enable_wind(req.seed);
  }
  if (hard.open_stretch || hard.wind) {
    scene_.world.rebuild();
  }
  if (hard.traffic) {
    traffic_ = std::make_unique<Traffic>(scene_.plan, *trajectory_, scene_.world.terrain, req.duration, req.seed);
  }

  // The LiDAR sits on a roof rack ~1 m above and ~0.5 m ahead of the IMU, mounted a few degrees
  // off from the IMU axes, and its clock runs a few ms behind the IMU's.
  Rng rng(derive_seed(req.seed, kMountStream));
  imu_from_lidar_.translation << 0.50 + rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05),
      1.05 + rng.uniform(-0.03, 0.03);
  const double roll = rng.sign() * rng.uniform(1.0, 3.0) * kDeg;
  const double pitch = rng.sign() * rng.uniform(1.0, 3.0) * kDeg;
  const double yaw = rng.sign() * rng.uniform(2.0, 5.0) * kDeg;
  imu_from_lidar_.rotation = rotation_from_euler(roll, pitch, yaw);
  time_offset_ = rng.uniform(0.002, 0.006);
  az_start_step_ = rng.uniform_int(0, kBlocksPerRev - 1);
  // Overrides come after every draw, so that the rest of the drive stays the seed's.
  if (config_.extrinsic_translation_m) imu_from_lidar_.translation = *config_.extrinsic_translation_m;
  if (config_.extrinsic_rpy_deg) {
    const Eigen::Vector3d& rpy = *config_.extrinsic_rpy_deg;
    imu_from_lidar_.rotation = rotation_from_euler(rpy.x() * kDeg, rpy.y() * kDeg, rpy.z() * kDeg);
  }
  if (config_.time_offset_s) time_offset_ = *config_.time_offset_s;

  lidar_params_.dual_return = config_.dual_return;
  lidar_noise_.enabled = config_.noise;
  lidar_noise_.angle_error_deg = config_.angle_error_deg;
  lidar_noise_.extra_dropout = hard.dropout;
  lidar_noise_.rain_rate = hard.rain_rate;
  if (hard.consumer_imu) {
    imu_noise_ = ImuNoise::bmi088();
  }
  imu_noise_.enabled = config_.noise;
  ego_ = EgoBody::passenger_car();
  if (config_.lidar == LidarKind::Hdl64e) {
    if (config_.dual_return || hard.traffic || hard.dropout > 0.0 || hard.rain_rate > 0.0) {
      throw std::invalid_argument("the HDL-64E takes no dual return, traffic, dropout or rain");
    }
    hdl_ = std::make_unique<Hdl64eModel>(HdlParams{}, lidar_noise_, imu_from_lidar_, config_.ego_body ? &ego_ : nullptr,
                                         req.seed);
    return;
  }
  const HeliosCalibration cal = load_angles_csv(config_.angles_csv);
  lidar_ = std::make_unique<LidarModel>(cal, lidar_params_, lidar_noise_, imu_from_lidar_,
                                        config_.ego_body ? &ego_ : nullptr, req.seed);
}

Pose Simulation::lidar_pose(double t) const {
  const Pose b = trajectory_->pose(t);
  return Pose{b.rotation * imu_from_lidar_.rotation,
              b.rotation * imu_from_lidar_.translation + b.translation};
}

RunReport Simulation::write_lidar(const std::string& path,
                                  const std::function<void(double)>& progress) const {
  RunReport report;
  PcapWriter pcap(path);
  const bool dual = config_.dual_return;
  const std::uint64_t per_packet = dual ? 6 : 12;
  // Firing g happens at LiDAR-clock time g * T (relative), i.e. IMU-clock time g * T + offset.
  const double last = config_.scene.duration - time_offset_ - 2.0 * kBlockPeriod;
  std::uint64_t total = static_cast<std::uint64_t>(std::floor(last / kBlockPeriod)) + 1;
  total -= total % per_packet;
  const std::uint64_t unit = kBlocksPerRev;
  const std::uint64_t units = (total + unit - 1) / unit;
  const int threads = std::max(1, config_.threads);
  const std::uint64_t batch = static_cast<std::uint64_t>(threads) * 2;

  Rng net(derive_seed(config_.scene.seed, kNetStream));
  const std::uint64_t epoch_us = static_cast<std::uint64_t>(config_.epoch_s) * 1000000U;
  // Signed: a LiDAR clock ahead of the IMU's has a negative offset.
  const std::int64_t offset_us = std::llround(time_offset_ * 1e6);
  std::uint64_t last_record_us = 0;
  std::uint32_t counter = 0;
  double next_difop = 0.3;
  std::array<std::uint8_t, 6> serial = {0x00, 0x15, 0x52, 0x10, 0x07, static_cast<std::uint8_t>(config_.scene.seed & 0xFFU)};
  Payload payload{};

  auto arrival = [&](std::uint64_t sent_lidar_us) {
    // Host clock = IMU clock; the packet leaves once complete and crosses a switch.
    const double latency_us = 180.0 + net.exponential(35.0);
    std::uint64_t t = static_cast<std::uint64_t>(static_cast<std::int64_t>(epoch_us + sent_lidar_us) + offset_us) +
                      static_cast<std::uint64_t>(latency_us);
    t = std::max(t, last_record_us + 11);  // 1290 bytes at 1 Gbit/s
    last_record_us = t;
    return t;
  };

  std::vector<std::vector<FiringResult>> results(static_cast<std::size_t>(batch));
  std::vector<std::uint64_t> rays(static_cast<std::size_t>(batch));
  for (std::uint64_t u0 = 0; u0 < units; u0 += batch) {
    const std::uint64_t n_units = std::min(batch, units - u0);
    auto work = [&](int tid) {
      for (std::uint64_t k = static_cast<std::uint64_t>(tid); k < n_units; k += static_cast<std::uint64_t>(threads)) {
        const std::uint64_t u = u0 + k;
        const std::uint64_t g0 = u * unit;
        const std::uint64_t g1 = std::min(total, g0 + unit);
        auto& out = results[static_cast<std::size_t>(k)];
        out.resize(static_cast<std::size_t>(g1 - g0));
        RayContext ctx(scene_.world, derive_seed(config_.scene.seed, kLidarStream, u));
        const double t0 = static_cast<double>(g0) * kBlockPeriod + time_offset_;
        const double t1 = static_cast<double>(g1) * kBlockPeriod + time_offset_;
        TrafficScratch traffic{traffic_.get(), {}, {}};
        if (traffic_) {
          // Range plus how far a vehicle and the car move in a revolution, plus a truck's half length.
          traffic_->near(t0, t1, lidar_pose(0.5 * (t0 + t1)).translation.head<2>(),
                         lidar_params_.max_range + 15.0, traffic.near);
        }
        Pose cur = lidar_pose(t0);
        for (std::uint64_t g = g0; g < g1; ++g) {
          const double t = static_cast<double>(g) * kBlockPeriod + time_offset_;
          const Pose next = lidar_pose(static_cast<double>(g + 1) * kBlockPeriod + time_offset_);
          const int az = static_cast<int>((static_cast<std::uint64_t>(az_start_step_) + g) % kBlocksPerRev);
          lidar_->fire(az, t, cur, next, scene_.world, traffic_ ? &traffic : nullptr, ctx,
                       out[static_cast<std::size_t>(g - g0)]);
          cur = next;
        }
        rays[static_cast<std::size_t>(k)] = (g1 - g0) * kChannels;
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) {
      pool.emplace_back(work, t);
    }
    work(0);
    for (auto& th : pool) {
      th.join();
    }
    // Packetise in order.
    for (std::uint64_t k = 0; k < n_units; ++k) {
      const auto& res = results[static_cast<std::size_t>(k)];
      report.rays += rays[static_cast<std::size_t>(k)];
      const std::uint64_t g0 = (u0 + k) * unit;
      for (std::size_t i = 0; i < res.size(); i += per_packet) {
        const std::uint64_t g = g0 + i;
        const std::uint64_t t_us = firing_time_us(g);
        const double t_s = static_cast<double>(g) * kBlockPeriod;
        if (t_s >= next_difop) {
          DifopInfo info;
          info.dual_return = dual;
          info.time_us = epoch_us + t_us;
          info.calibration = &lidar_->published();
          info.serial = serial;
          encode_difop(info, payload);
          pcap.write_udp(arrival(t_us), 7788, payload);
          ++report.difop_packets;
          next_difop += 1.0;
        }
        std::array<const FiringResult*, 12> blocks{};
        std::array<bool, 12> second{};
        for (std::size_t b = 0; b < 12; ++b) {
          const std::size_t f = dual ? i + b / 2 : i + b;
          blocks[b] = &res[f];
          second[b] = dual && (b % 2 == 1);
          const auto& ch = second[b] ? res[f].second : res[f].first;
          for (const auto& c : ch) {
            report.returns += c.raw != 0 ? 1U : 0U;
          }
        }
        MsopHeader h;
        h.counter = counter++;
        h.time_us = epoch_us + t_us;
        h.temperature_c = 41.0 + 4.0 * std::sin(t_s / 400.0);
        encode_msop(h, blocks, second, payload);
        pcap.write_udp(arrival(firing_time_us(g + per_packet)), 6699, payload);
        ++report.msop_packets;
      }
    }
    if (progress) {
      progress(static_cast<double>(std::min(units, u0 + batch)) / static_cast<double>(units));
    }
  }
  return report;
}

}  // namespace liod::sim
