#include "fault_drive.hpp"

#include <map>
#include <memory>
#include <string>

#include "liod/eval/io.hpp"
#include "simulated_drive.hpp"

namespace liod::test {
namespace {

/// The drive liod-sim makes with `arguments`, in test-data/`name` (shared by the test processes,
/// see simulated_drive.hpp), or null when liod-sim is not built or failed.
const FaultDrive* simulated_drive(const std::string& name, const std::string& arguments) {
  static std::map<std::string, std::unique_ptr<FaultDrive>> drives;  // null: tried and failed
  if (const auto it = drives.find(name); it != drives.end()) return it->second.get();
  auto& drive = drives[name];
  const auto dir = cached_drive_dir(name, arguments);
  if (dir.empty()) return nullptr;
  auto d = std::make_unique<FaultDrive>();
  d->dir = dir;
  d->recording = fault::read_recording(dir / "lidar.pcap", dir / "imu.csv");
  d->truth = eval::read_tum((dir / "groundtruth.tum").string());
  drive = std::move(d);
  return drive.get();
}

}  // namespace

const FaultDrive* fault_drive() {
  return simulated_drive("fault-drive", "--route urban --seed 1 --duration 25 --max-speed 12");
}

const FaultDrive* rails_drive() {
  return simulated_drive("rails-drive", "--route highway --seed 2 --duration 8 --max-speed 12");
}

const FaultDrive* posts_drive() {
  return simulated_drive("posts-drive", "--route highway --seed 4 --duration 12 --max-speed 12");
}

const FaultDrive* rest_drive() {
  return simulated_drive("rest-drive", "--route highway --seed 1 --duration 12 --max-speed 12 --static-start");
}

const FaultDrive* aliasing_posts_drive() {
  return simulated_drive("aliasing-posts-drive", "--route highway --seed 108 --duration 6 --max-speed 15");
}

const FaultDrive* backward_alias_drive() {
  return simulated_drive("backward-alias-drive", "--route highway --seed 9 --duration 8 --max-speed 15");
}

const FaultDrive* grid_edge_alias_drive() {
  return simulated_drive("grid-edge-alias-drive", "--route highway --seed 53 --duration 6 --max-speed 15");
}

const FaultDrive* tunnel_rest_drive() {
  return simulated_drive("tunnel-rest-drive", "--route tunnel --seed 1 --duration 25 --max-speed 15");
}

const FaultDrive* move_off_drive() {
  return simulated_drive("move-off-drive", "--route highway --seed 4 --duration 8 --max-speed 15 --static-start");
}

const FaultDrive* tunnel_move_off_drive() {
  return simulated_drive("tunnel-move-off-drive", "--route tunnel --seed 9 --duration 25 --max-speed 15");
}

const FaultDrive* gantries_drive() {
  return simulated_drive("gantries-drive",
                         "--route highway --seed 8 --duration 50 --max-speed 15 --no-noise --angle-error-deg 0");
}

const FaultDrive* tunnel_heading_drive() {
  return simulated_drive("tunnel-heading-drive",
                         "--route tunnel --seed 10 --duration 40 --max-speed 15 --no-noise --angle-error-deg 0");
}

const FaultDrive* rail_faces_drive() {
  return simulated_drive("rail-faces-drive", "--route highway --seed 131 --duration 8 --max-speed 13");
}

const FaultDrive* parked_car_drive() {
  return simulated_drive("parked-car-drive", "--route highway --seed 7 --duration 12 --max-speed 12");
}

const FaultDrive* crest_start_drive() {
  return simulated_drive("crest-start-drive", "--route highway --seed 7 --duration 60 --max-speed 15");
}

const FaultDrive* reboot_drive() {
  return simulated_drive("reboot-drive", "--route urban --seed 1 --duration 60 --max-speed 12");
}

const FaultDrive* tunnel_yaw_bias_drive() {
  return simulated_drive("tunnel-yaw-bias-drive", "--route tunnel --seed 7 --duration 40 --max-speed 15");
}

}  // namespace liod::test
