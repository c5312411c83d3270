// Simulation speed: seconds of drive simulated per second of wall time (10 s urban drive).

#include <benchmark/benchmark.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "liod/sim/simulator.hpp"

namespace {

void BM_Urban10s(benchmark::State& state) {
  liod::sim::SimConfig c;
  c.scene.route = liod::sim::RouteKind::Urban;
  c.scene.seed = 1;
  c.scene.duration = 10.0;
  c.scene.max_speed = 12.0;
  c.threads = static_cast<int>(state.range(0));
  c.angles_csv = std::string(LIOD_SHARED_DIR) + "/data/robosense/helios32_angles.csv";
  const auto dir = std::filesystem::temp_directory_path() / "liod-bench-sim";
  std::filesystem::create_directories(dir);
  c.out_dir = dir.string();
  double wall = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const liod::sim::Simulation sim(c);
    sim.write_all();
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  state.counters["sim_s_per_wall_s"] = c.scene.duration / wall;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_Urban10s)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();

}  // namespace
