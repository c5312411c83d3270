// Per-scan cost of the front end on a simulated RS-Helios-5515 drive, one core. The drive comes
// from LIOD_BENCH_DRIVE (a liod-sim output directory) or is simulated on the spot (20 s urban,
// 12 m/s) with the built liod-sim. Prints median / p99 per scan of the whole process() (median_ms,
// p99_ms, max_ms: deskew + features + registration + the map's upkeep), of the front end
// alone (front_median_ms, front_p99_ms: deskew + features + registration, as timed inside
// process()), of the map's upkeep (map_median_ms), and the replay speed against real time.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <stdexcept>

#include "liod/config.hpp"
#include "liod/daemon/percentile.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/lidar_inertial_odometry.hpp"

namespace {

namespace fs = std::filesystem;

struct Drive {
  std::vector<liod::Scan> scans;
  std::vector<liod::ImuSample> imu;
  liod::Config config;
};

fs::path drive_directory() {
  if (const char* dir = std::getenv("LIOD_BENCH_DRIVE")) return dir;
  const fs::path dir = fs::temp_directory_path() / "liod_bench_drive";
  if (!fs::exists(dir / "groundtruth.tum")) {
    fs::create_directories(dir);
    const std::string cmd = std::string(LIOD_BINARY_DIR) + "/bin/liod-sim --route urban --seed 7 --duration 20 "
                            "--max-speed 12 --quiet --out " + dir.string();
    if (std::system(cmd.c_str()) != 0) throw std::runtime_error("could not simulate a drive: " + cmd);
  }
  return dir;
}

const Drive& drive() {
  static const Drive loaded = [] {
    const fs::path dir = drive_directory();
    Drive d;
    d.config = liod::load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml",
                                  std::string(LIOD_SOURCE_DIR) + "/config/vehicles/liod-sim-car.yaml",
                                  (dir / "extrinsics.yaml").string()});
    liod::drivers::HeliosOptions options;
    liod::drivers::RsHeliosDecoder decoder(options, [&](liod::Scan& scan, const liod::drivers::SweepInfo&) {
      d.scans.push_back(scan);
    });
    liod::drivers::PcapReader pcap(dir / "lidar.pcap");
    liod::drivers::UdpDatagram datagram;
    while (pcap.next(datagram)) decoder.feed(datagram.payload, datagram.capture_time_ns);
    d.imu = liod::drivers::read_imu_csv(dir / "imu.csv");
    return d;
  }();
  return loaded;
}

void BM_FrontEndPerScan(benchmark::State& state) {
  const Drive& d = drive();
  std::vector<double> per_scan_ms;
  std::vector<double> front_ms;
  std::vector<double> map_ms;
  double wall_s = 0.0;
  for (auto _ : state) {
    liod::LidarInertialOdometry odometry(d.config);
    std::size_t next_imu = 0;
    per_scan_ms.clear();
    front_ms.clear();
    map_ms.clear();
    const auto start = std::chrono::steady_clock::now();
    for (const auto& scan : d.scans) {
      const double end = odometry.scan_end_time(scan);
      while (next_imu < d.imu.size() && d.imu[next_imu].time <= end + 0.02) odometry.add_imu(d.imu[next_imu++]);
      const auto t0 = std::chrono::steady_clock::now();
      const auto result = odometry.process(scan);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (result && !(result->status & liod::kStatusInitializing)) {
        per_scan_ms.push_back(ms);
        front_ms.push_back(result->deskew_ms + result->features_ms + result->registration_ms);
        map_ms.push_back(result->map_ms);
      }
      benchmark::DoNotOptimize(result);
    }
    wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::size_t points = 0;
  for (const auto& s : d.scans) points += s.points.size();
  state.counters["scans"] = static_cast<double>(per_scan_ms.size());
  state.counters["points_per_scan"] = static_cast<double>(points) / static_cast<double>(std::max<std::size_t>(1, d.scans.size()));
  state.counters["median_ms"] = liod::percentile(per_scan_ms, 0.5);
  state.counters["p99_ms"] = liod::percentile(per_scan_ms, 0.99);
  state.counters["max_ms"] = liod::percentile(per_scan_ms, 1.0);
  state.counters["front_median_ms"] = liod::percentile(front_ms, 0.5);
  state.counters["front_p99_ms"] = liod::percentile(front_ms, 0.99);
  state.counters["map_median_ms"] = liod::percentile(map_ms, 0.5);
  state.counters["x_real_time"] = wall_s > 0 ? static_cast<double>(d.scans.size()) * 0.1 / wall_s : 0.0;
}
BENCHMARK(BM_FrontEndPerScan)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
