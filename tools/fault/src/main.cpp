// liod-fault: rewrites a recording (LiDAR pcap + IMU CSV) with injected faults (see README.md).
#include <CLI/CLI.hpp>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "liod/fault/apply_fault.hpp"

int main(int argc, char** argv) {
  CLI::App app{"liod-fault: inject faults into a recorded drive (pcap + IMU CSV) for `liod replay`"};
  std::string pcap;
  std::string imu;
  std::string out;
  std::vector<std::string> specs;
  std::uint64_t seed = 1;
  app.add_option("--pcap", pcap, "input LiDAR capture")->required();
  app.add_option("--imu", imu, "input IMU CSV")->required();
  app.add_option("--out", out, "output directory (lidar.pcap, imu.csv)")->required();
  app.add_option("--fault", specs, "kind:key=value,... (repeatable, applied in order): " + liod::fault::fault_syntax())
      ->required();
  app.add_option("--seed", seed, "random choices (same seed, same output)")->default_val(1);
  CLI11_PARSE(app, argc, argv);
  try {
    std::vector<liod::fault::Fault> faults;
    for (const auto& s : specs) faults.push_back(liod::fault::parse_fault(s));
    auto recording = liod::fault::read_recording(pcap, imu);
    for (std::size_t i = 0; i < faults.size(); ++i) {
      std::cout << liod::fault::apply_fault(faults[i], recording, seed + i) << '\n';
    }
    std::filesystem::create_directories(out);
    const std::filesystem::path dir(out);
    liod::fault::write_recording(recording, dir / "lidar.pcap", dir / "imu.csv");
    std::cout << "wrote " << (dir / "lidar.pcap").string() << " (" << recording.packets.size() << " datagrams) and "
              << (dir / "imu.csv").string() << " (" << recording.imu.size() << " samples)\n";
  } catch (const std::exception& e) {
    std::cerr << "liod-fault: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
