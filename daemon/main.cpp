// liod: the one command-line entry point. Each subcommand parses its options, loads and
// validates the configuration (exiting non-zero before doing anything on an error), then runs.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <iostream>

#include "liod/config.hpp"
#include "liod/daemon/decode_command.hpp"
#include "liod/daemon/logging.hpp"

namespace {

constexpr int kConfigErrorExit = 2;

int check_config(const std::vector<std::string>& paths) {
  liod::load_config(paths);
  std::cout << "configuration OK:";
  for (const auto& p : paths) std::cout << ' ' << p;
  std::cout << '\n';
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"liod " LIOD_VERSION ": LiDAR-inertial odometry and SLAM for the RS-Helios + IMU, without ROS"};
  app.set_version_flag("--version", "liod " LIOD_VERSION);
  app.require_subcommand(1);
  std::string log_level;
  app.add_option("--log-level", log_level, "trace|debug|info|warn|error|critical|off (overrides log.level)");

  auto* check = app.add_subcommand("check-config", "Load and validate configuration files, then exit");
  std::vector<std::string> check_paths;
  check->add_option("--config", check_paths, "configuration file(s), later ones override")->required()->check(CLI::ExistingFile);

  auto* decode = app.add_subcommand("decode", "Decode RS-Helios packets from a pcap into sweeps (PCD)");
  liod::DecodeOptions decode_options;
  decode->add_option("--pcap", decode_options.pcap, "capture file (pcap or pcapng)")->required();
  decode->add_option("--angles", decode_options.angles_csv, "calibration CSV (vertical_deg,horizontal_deg) used until a DIFOP arrives");
  decode->add_option("--out", decode_options.out_dir, "directory for one PCD file per sweep");

  CLI11_PARSE(app, argc, argv);

  try {
    liod::setup_logging(log_level.empty() ? "info" : log_level);
    if (*check) return check_config(check_paths);
    if (*decode) return liod::run_decode(decode_options, std::cout);
  } catch (const liod::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kConfigErrorExit;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
