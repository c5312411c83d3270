// Same seed -> same bytes (whatever the thread count); different seeds -> different drives.

#include <gtest/gtest.h>

#include "sim_test_util.hpp"

namespace liod::sim::test {
namespace {

const char* kFiles[] = {"lidar.pcap", "imu.csv", "groundtruth.tum", "extrinsics.yaml", "scenario.yaml"};

TEST(SimDeterminism, SameSeedSameBytesDifferentSeedDifferentDrive) {
  LIOD_SIM_REQUIRE_SHARED();
  const std::string a = scratch_dir("det-a");
  const std::string b = scratch_dir("det-b");
  const std::string c = scratch_dir("det-c");
  SimConfig ca = short_config(RouteKind::Urban, 7, 2.0, a);
  ca.threads = 2;
  SimConfig cb = ca;
  cb.out_dir = b;
  cb.threads = 1;  // thread count must not change a byte
  SimConfig cc = ca;
  cc.out_dir = c;
  cc.scene.seed = 8;
  Simulation(ca).write_all();
  Simulation(cb).write_all();
  Simulation(cc).write_all();
  for (const char* f : kFiles) {
    const std::string fa = slurp(a + "/" + f);
    ASSERT_FALSE(fa.empty()) << f;
    EXPECT_EQ(fa, slurp(b + "/" + f)) << f << " differs between identical runs";
  }
  EXPECT_NE(slurp(a + "/lidar.pcap"), slurp(c + "/lidar.pcap"));
  EXPECT_NE(slurp(a + "/imu.csv"), slurp(c + "/imu.csv"));
  EXPECT_NE(slurp(a + "/groundtruth.tum"), slurp(c + "/groundtruth.tum"));
  EXPECT_NE(slurp(a + "/extrinsics.yaml"), slurp(c + "/extrinsics.yaml"));
}

TEST(SimDeterminism, EveryRouteBuildsAndDrives) {
  LIOD_SIM_REQUIRE_SHARED();
  for (RouteKind r : {RouteKind::Urban, RouteKind::Loop, RouteKind::Figure8, RouteKind::Highway,
                      RouteKind::Tunnel}) {
    SimConfig c = short_config(r, 3, 30.0, "");
    c.scene.max_speed = 15.0;
    const Simulation sim(c);
    EXPECT_GT(sim.drive_stats().distance, 100.0) << route_name(r);
    EXPECT_LE(sim.drive_stats().top_speed, 15.0 + 0.3) << route_name(r);
    EXPECT_LE(sim.drive_stats().peak_lateral_accel, 3.3) << route_name(r);
    EXPECT_GT(sim.scene().world.primitive_count(), 100U) << route_name(r);
  }
}

}  // namespace
}  // namespace liod::sim::test
