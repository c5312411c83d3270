// bench_long_drive: memory and per-scan time over a long simulated drive (issue 7, resource
// bounds). Simulates a drive once (default `liod-sim --route loop --seed 1 --duration 1800
// --max-speed 12`, kept in build/test-data/long-drive-*/), replays it with `liod replay` in a
// child process, odometry only and then with the backend on (config/examples/slam.yaml), and
// prints for each the child's peak RSS (getrusage ru_maxrss), its RSS along the run, and the
// front-end time per scan (deskew + features + registration, from --scan-log) in the first and
// in the last minute of the drive. Prints figures; exits non-zero only when a step fails.
// See docs/robustness.md.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "liod/daemon/percentile.hpp"

namespace fs = std::filesystem;

namespace {

constexpr double kRssBoundMb = 1536.0;  // issue 7: peak RSS <= 1.5 GB over 30 minutes

struct ScanTiming {
  double time = 0.0;
  double front_end_ms = 0.0;  ///< deskew + features + registration
  double features_ms = 0.0;
  double map_ms = 0.0;
};

/// Simulates the drive unless `dir` already holds it (a stamp file names the arguments).
bool simulate(const fs::path& dir, const std::string& sim_args) {
  const auto stamp = dir / "complete";
  if (fs::exists(stamp)) {
    std::ifstream in(stamp);
    std::string made_with;
    std::getline(in, made_with);
    if (made_with == sim_args) {
      std::cout << "drive: " << sim_args << " (already simulated in " << dir.string() << ")\n";
      return true;
    }
  }
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto start = std::chrono::steady_clock::now();
  const std::string cmd = std::string(LIOD_BINARY_DIR) + "/bin/liod-sim " + sim_args + " --quiet --out " + dir.string();
  if (std::system(cmd.c_str()) != 0) {
    std::cerr << "bench_long_drive: simulation failed: " << cmd << '\n';
    return false;
  }
  std::ofstream(stamp) << sim_args << '\n';
  std::cout << "drive: " << sim_args << " (simulated in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s)\n";
  return true;
}

long rss_kb(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  }
  return 0;
}

/// Runs `argv` as a child; samples its RSS every 0.5 s into `rss`; returns its exit status and
/// resource usage.
int run_child(const std::vector<std::string>& argv, std::vector<long>& rss, rusage& usage) {
  const pid_t child = ::fork();
  if (child < 0) return -1;
  if (child == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  for (;;) {
    const pid_t done = ::wait4(child, &status, WNOHANG, &usage);
    if (done == child) break;
    rss.push_back(rss_kb(child));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<ScanTiming> read_scan_log(const fs::path& path) {
  std::vector<ScanTiming> out;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header: time,status,...,deskew_ms,features_ms,registration_ms,map_ms,(state)
  while (std::getline(in, line)) {
    std::vector<double> f;
    std::istringstream s(line);
    std::string field;
    while (std::getline(s, field, ',')) f.push_back(std::strtod(field.c_str(), nullptr));
    if (f.size() < 14) continue;
    out.push_back({f[0], f[10] + f[11] + f[12], f[11], f[13]});
  }
  return out;
}

// The feature extraction does the same work on every scan (~50k points, nothing kept between
// scans), so its time is a yardstick of the machine's load: front end / features is the figure
// that shows a growth of the odometry's own cost on a machine shared with other work.
void print_window(const char* name, const std::vector<ScanTiming>& scans, double from, double to) {
  std::vector<double> front;
  std::vector<double> features;
  std::vector<double> map;
  for (const auto& s : scans) {
    if (s.time < from || s.time >= to) continue;
    front.push_back(s.front_end_ms);
    features.push_back(s.features_ms);
    map.push_back(s.map_ms);
  }
  const double features_median = liod::percentile(features, 0.5);
  std::printf("%-17s %5zu scans | front end median %5.2f  p90 %5.2f  p99 %5.2f  max %6.2f ms | features median %4.2f ms, "
              "front end / features %4.2f | map update median %4.2f  p99 %5.2f ms\n",
              name, front.size(), liod::percentile(front, 0.5), liod::percentile(front, 0.9),
              liod::percentile(front, 0.99), liod::percentile(front, 1.0), features_median,
              features_median > 0 ? liod::percentile(front, 0.5) / features_median : 0.0, liod::percentile(map, 0.5),
              liod::percentile(map, 0.99));
}

// One replay of the drive in a child process; prints its figures. False when a step failed.
bool replay_and_report(const fs::path& drive, bool backend) {
  const std::string source = LIOD_SOURCE_DIR;
  const std::string name = backend ? "backend" : "odometry";
  std::vector<std::string> replay{std::string(LIOD_BINARY_DIR) + "/bin/liod", "replay",
                                  "--config", source + "/config/liod.yaml",
                                  "--config", source + "/config/vehicles/liod-sim-car.yaml",
                                  "--config", (drive / "extrinsics.yaml").string()};
  if (backend) {
    // The backend's keyframe clouds beyond backend.memory_keyframes go to a scratch directory
    // under the state directory: here, next to the drive (not /var/lib/liod).
    const fs::path state = drive / "state";
    fs::create_directories(state);
    std::ofstream(drive / "bench_state_dir.yaml") << "output: {state_dir: " << state.string() << "}\n";
    replay.insert(replay.end(), {"--config", source + "/config/examples/slam.yaml", "--config",
                                 (drive / "bench_state_dir.yaml").string()});
  }
  const fs::path scan_log = drive / ("scan_log_" + name + ".csv");
  replay.insert(replay.end(), {"--pcap", (drive / "lidar.pcap").string(), "--imu", (drive / "imu.csv").string(),
                               "--trajectory", (drive / ("replay_" + name + ".tum")).string(), "--scan-log",
                               scan_log.string()});
  std::cout << "replay" << (backend ? " (backend on: config/examples/slam.yaml)" : " (odometry only)") << ":"
            << std::endl;
  std::vector<long> rss;
  rusage usage{};
  const auto start = std::chrono::steady_clock::now();
  const int code = run_child(replay, rss, usage);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (code != 0) {
    std::cerr << "bench_long_drive: liod replay exited with " << code << '\n';
    return false;
  }

  const double peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  std::printf("[%s] wall time of the replay %.0f s\n", name.c_str(), wall_s);
  std::printf("[%s] peak RSS of the replay process: %.0f MB (issue 7 bound %.0f MB: %s)\n", name.c_str(), peak_mb,
              kRssBoundMb, peak_mb <= kRssBoundMb ? "within" : "EXCEEDED");
  std::printf("[%s] RSS along the replay (each 10 %% of its wall time):", name.c_str());
  for (int k = 1; k <= 10 && !rss.empty(); ++k) {
    std::printf(" %ld", rss[std::min(rss.size() - 1, rss.size() * static_cast<std::size_t>(k) / 10)] / 1024);
  }
  std::printf(" MB\n");

  const auto scans = read_scan_log(scan_log);
  if (scans.size() < 1200) {
    std::cerr << "bench_long_drive: the scan log has " << scans.size() << " scans, too few for two minutes\n";
    return false;
  }
  const double first = scans.front().time;
  const double last = scans.back().time;
  print_window(("[" + name + "] first").c_str(), scans, first, first + 60.0);
  print_window(("[" + name + "] last").c_str(), scans, last - 60.0, last + 1.0);
  print_window(("[" + name + "] whole").c_str(), scans, first, last + 1.0);
  std::fflush(stdout);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bench_long_drive: peak RSS and per-scan time of `liod replay` over a long simulated drive"};
  std::string route = "loop";
  int seed = 1;
  double minutes = 30.0;
  double max_speed = 12.0;
  std::string dir;
  std::string only;
  app.add_option("--route", route, "liod-sim route")->default_val("loop");
  app.add_option("--seed", seed, "liod-sim seed")->default_val(1);
  app.add_option("--minutes", minutes, "drive length")->default_val(30.0);
  app.add_option("--max-speed", max_speed, "m/s")->default_val(12.0);
  app.add_option("--dir", dir, "where the drive is simulated and kept (default: build/test-data/long-drive-...)");
  app.add_option("--only", only, "run one replay: odometry (backend off) or backend (config/examples/slam.yaml)")
      ->check(CLI::IsMember({"odometry", "backend"}));
  bool backend_flag = false;
  app.add_flag("--backend", backend_flag, "the same as --only backend");
  CLI11_PARSE(app, argc, argv);
  if (backend_flag) only = "backend";

  std::ostringstream sim_args;
  sim_args << "--route " << route << " --seed " << seed << " --duration " << minutes * 60.0 << " --max-speed " << max_speed;
  const fs::path drive = dir.empty() ? fs::path(LIOD_BINARY_DIR) / "test-data" /
                                           ("long-drive-" + route + "-" + std::to_string(seed) + "-" +
                                            std::to_string(static_cast<int>(minutes)) + "min")
                                     : fs::path(dir);
  if (!simulate(drive, sim_args.str())) return 1;
  if (only != "backend" && !replay_and_report(drive, false)) return 1;
  if (only != "odometry" && !replay_and_report(drive, true)) return 1;
  return 0;
}
