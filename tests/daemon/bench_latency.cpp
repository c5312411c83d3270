// Latency benchmark (prints figures): the simulated drive sent over loopback UDP at recorded pace
// into the live pipeline (UDP LiDAR source, IMU log at recorded pace, pose socket with a client).
//  - scan: the packet that completes a sweep leaves the sender -> its pose arrives at the client
//    (end to end, measured by the client), and the pipeline's own figure (kernel arrival of that
//    packet -> written to the socket);
//  - IMU: sample handed to the pipeline -> its IMU-rate pose written to the socket.
// Scan latency is printed for all scans and for the steady state: the first 2 s of poses are the
// start-up (gravity alignment, the rolling start's speed search, the map restarted once the speed
// is known), each a one-off several times the cost of a scan.
// With the backend on (--config config/examples/slam.yaml) it also shows what the backend costs
// the odometry on the same cores: compare the odometry stage with a run without it, on a drive
// that closes loops (e.g. liod-sim --route loop --duration 120).
// With --viewers N, N Foxglove clients (foxglove_client.hpp) subscribe to every channel of the
// live view for the whole drive: compare the scan latency with --viewers 0.
// Usage: bench_latency [--drive DIR] [--config FILE]... [--viewers N]
//   (default drive: a 30 s urban drive generated with liod-sim into /tmp)
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>

#include "foxglove_client.hpp"
#include "udp_sender.hpp"
#include "liod/daemon/foxglove_server.hpp"
#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/pose_client.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/drivers/rs_helios.hpp"

using namespace liod;

namespace {
double pct(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

// The figures depend on what else runs: print the load average next to them.
std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

void print_stage(const char* name, const LatencyStats::Summary& s) {
  std::printf("  %-34s median %6.2f ms, p99 %6.2f ms, max %6.2f ms\n", name, s.median_us / 1e3, s.p99_us / 1e3, s.max_us / 1e3);
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liod latency benchmark: a drive over loopback UDP at recorded pace"};
  std::filesystem::path drive = "/tmp/liod-bench-drive-30s";
  std::vector<std::string> extra_configs;
  app.add_option("--drive", drive, "liod-sim output directory (generated if absent)");
  app.add_option("--config", extra_configs, "config file layered after config/liod.yaml (repeatable)");
  int viewers = 0;
  app.add_option("--viewers", viewers, "Foxglove clients subscribed to every channel of the live view (0: the view off)");
  CLI11_PARSE(app, argc, argv);
  if (!std::filesystem::exists(drive / "lidar.pcap")) {
    std::filesystem::create_directories(drive);
    const std::string cmd = std::string(LIOD_BINARY_DIR) + "/bin/liod-sim --route urban --seed 3 --duration 30 --max-speed 12 --out " + drive.string();
    std::printf("generating the drive: %s\n", cmd.c_str());
    if (std::system(cmd.c_str()) != 0) return 1;
  }
  std::vector<std::string> files{std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml"};
  files.insert(files.end(), extra_configs.begin(), extra_configs.end());
  files.push_back((drive / "extrinsics.yaml").string());
  Config config = load_config(files);
  config.backend.persist = false;  // a benchmark leaves no state behind
  const auto port = static_cast<std::uint16_t>(50000 + ::getpid() % 5000 * 2);
  config.lidar.msop_port = port;
  config.lidar.difop_port = port + 1;
  config.drivers.lidar.bind_address = "127.0.0.1";
  config.time.lidar_clock = LidarClock::kSensor;
  config.output.pose_socket = "/tmp/liod-bench-" + std::to_string(::getpid()) + ".sock";
  config.threads.scan_ring = 64;

  // Which packet completes each sweep (sweep end time -> packet index), from the file.
  std::map<double, std::size_t> sweep_packet;
  {
    drivers::PcapReader reader(drive / "lidar.pcap");
    reader.set_port_filter({6699, 7788});
    std::size_t index = 0;
    drivers::HeliosOptions ho;
    drivers::RsHeliosDecoder dec(ho, [&](Scan& s, const drivers::SweepInfo&) { sweep_packet[s.end_time] = index; });
    drivers::UdpDatagram d;
    while (reader.next(d)) {
      dec.feed(d.payload, d.capture_time_ns);
      ++index;
    }
  }
  PipelineOptions po;
  po.ordering = Ordering::Arrival;
  po.pose_socket = config.output.pose_socket;
  po.bridge_clock_steps = true;  // as liod run
  std::vector<std::unique_ptr<test::FoxgloveClient>> clients;
  if (viewers > 0) {
    po.viewer = std::make_shared<FoxgloveServer>(config.viewer, config.extrinsics, 0);
    for (int i = 0; i < viewers; ++i) {
      clients.push_back(std::make_unique<test::FoxgloveClient>(po.viewer->port()));
      clients.back()->subscribe();
      clients.back()->start();
    }
  }
  Pipeline pipeline(config, po);
  std::vector<double> front_end_ms, map_ms;  // the odometry's own split of its time (publisher thread)
  pipeline.add_sink([&](const PoseEvent& ev) {
    if (ev.message.type != pose::MessageType::ScanPose) return;
    front_end_ms.push_back(ev.diagnostics.deskew_ms + ev.diagnostics.features_ms + ev.diagnostics.registration_ms);
    map_ms.push_back(ev.diagnostics.map_ms);
  });
  std::printf("load average before: %s (%u CPUs)\n", load_average().c_str(), std::thread::hardware_concurrency());
  auto pace = std::make_shared<PaceClock>();
  pace->pace = 1.0;
  pace->data_start_ns = first_imu_time_ns((drive / "imu.csv").string());
  pace->host_start_steady_ns = steady_ns();
  pipeline.start(std::make_unique<UdpLidarSource>(config), std::make_unique<CsvImuSource>((drive / "imu.csv").string(), pace));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  PoseClient client(config.output.pose_socket);
  std::vector<std::int64_t> send_ns;  // steady time each packet left the sender
  send_ns.reserve(20000);
  std::atomic<bool> sending{true};
  std::vector<std::pair<double, std::int64_t>> received;  // pose time, steady arrival
  std::thread reader([&] {
    pose::Message m;
    // Health messages keep arriving, so the loop is bounded by the flag, not by a read timeout.
    while (sending.load()) {
      if (!client.read(m, std::chrono::milliseconds(200))) continue;
      if (m.type == pose::MessageType::ScanPose) received.emplace_back(m.pose.time, steady_ns());
    }
  });
  // The sender, with a send-time log (same pacing as the tests' sender).
  {
    const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    drivers::PcapReader r(drive / "lidar.pcap");
    r.set_port_filter({6699, 7788});
    drivers::UdpDatagram d;
    std::int64_t first = -1;
    const auto start = std::chrono::steady_clock::now();
    while (r.next(d)) {
      if (first < 0) first = d.capture_time_ns;
      const auto due = start + std::chrono::nanoseconds(d.capture_time_ns - first);
      while (std::chrono::steady_clock::now() + std::chrono::microseconds(200) < due) std::this_thread::sleep_for(std::chrono::microseconds(100));
      while (std::chrono::steady_clock::now() < due) {
      }
      sockaddr_in to{};
      to.sin_family = AF_INET;
      to.sin_port = htons(d.dst_port == 6699 ? port : port + 1);
      to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      send_ns.push_back(steady_ns());
      ::sendto(fd, d.payload.data(), d.payload.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    }
    ::close(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  sending = false;
  reader.join();
  pipeline.drain(std::chrono::milliseconds(3000));
  std::vector<double> e2e_ms, steady_e2e_ms;
  const double offset = config.extrinsics.lidar_time_offset_s;
  constexpr double kStartUpS = 2.0;
  for (const auto& [t, arrival] : received) {
    const auto it = sweep_packet.lower_bound(t - offset - 1e-6);
    if (it == sweep_packet.end() || std::abs(it->first + offset - t) > 1e-6 || it->second >= send_ns.size()) continue;
    e2e_ms.push_back(static_cast<double>(arrival - send_ns[it->second]) * 1e-6);
    if (t - received.front().first >= kStartUpS) steady_e2e_ms.push_back(e2e_ms.back());
  }
  const auto sl = pipeline.scan_latency();
  const auto il = pipeline.imu_latency();
  std::printf("scan poses: %zu received, %zu matched to their completing packet\n", received.size(), e2e_ms.size());
  std::printf("scan latency, last packet sent -> pose at client: median %.2f ms, p99 %.2f ms, max %.2f ms\n", pct(e2e_ms, 0.5),
              pct(e2e_ms, 0.99), e2e_ms.empty() ? 0.0 : *std::max_element(e2e_ms.begin(), e2e_ms.end()));
  std::printf("  the same after the first %.0f s (steady state, n=%zu): median %.2f ms, p99 %.2f ms, max %.2f ms\n", kStartUpS,
              steady_e2e_ms.size(), pct(steady_e2e_ms, 0.5), pct(steady_e2e_ms, 0.99),
              steady_e2e_ms.empty() ? 0.0 : *std::max_element(steady_e2e_ms.begin(), steady_e2e_ms.end()));
  std::printf("scan latency, packet arrival -> pose written (pipeline): median %.2f ms, p99 %.2f ms (n=%zu)\n", sl.median_us / 1e3,
              sl.p99_us / 1e3, sl.count);
  const auto stages = pipeline.scan_stages();
  print_stage("socket (kernel -> LiDAR thread):", stages.receive);
  print_stage("ring + wait for IMU data:", stages.wait);
  print_stage("odometry (process):", stages.process);
  print_stage("pose ring -> written to the socket:", stages.publish);
  std::printf("  odometry split: front end median %.2f ms, p99 %.2f ms; map update median %.2f ms, p99 %.2f ms\n",
              pct(front_end_ms, 0.5), pct(front_end_ms, 0.99), pct(map_ms, 0.5), pct(map_ms, 0.99));
  std::printf("IMU latency, sample in -> IMU-rate pose written (pipeline): median %.1f us, p99 %.1f us, max %.1f us (n=%zu)\n",
              il.median_us, il.p99_us, il.max_us, il.count);
  if (po.viewer) {
    const auto v = po.viewer->stats();
    std::printf("live view: %d viewers; %llu messages sent, %llu dropped from slow viewers, %llu posts dropped; the first viewer "
                "received %zu scans, %zu maps, %zu poses\n", viewers, static_cast<unsigned long long>(v.messages_sent),
                static_cast<unsigned long long>(v.messages_dropped), static_cast<unsigned long long>(v.posts_dropped),
                clients[0]->count("/liod/scan"), clients[0]->count("/liod/map"), clients[0]->count("/liod/pose/odom"));
  }
  std::printf("load average after: %s\n", load_average().c_str());
  pipeline.join();
  if (auto* backend = pipeline.backend()) std::printf("%s", backend->summary().c_str());
  return 0;
}
