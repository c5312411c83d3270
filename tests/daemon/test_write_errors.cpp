// Output files that cannot be written (a full disk: /dev/full) are an error, not a silent
// truncation: `liod replay` still runs to the end, says which output failed and exits non-zero.
#include <gtest/gtest.h>

#include <sstream>

#include "reference_replay.hpp"
#include "sim_drive.hpp"

using namespace liod;
using namespace liod::test;

namespace {

struct ReplayResult {
  int exit_code = 0;
  std::string output;
};

ReplayResult replay_with(const std::filesystem::path& drive, const std::function<void(ReplayOptions&)>& edit) {
  const ScratchDir dir("write-errors");
  ReplayOptions o;
  o.pcap = (drive / "lidar.pcap").string();
  o.imu_csv = (drive / "imu.csv").string();
  o.trajectory_tum = (dir / "scan.tum").string();
  edit(o);
  std::ostringstream out;
  ReplayResult r;
  r.exit_code = run_replay(drive_config(drive), o, out);
  r.output = out.str();
  return r;
}

}  // namespace

TEST(WriteErrors, ReplayTrajectoryToAFullDisk) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto r = replay_with(*drive, [](ReplayOptions& o) { o.trajectory_tum = "/dev/full"; });
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("replay: "), std::string::npos) << r.output;  // ran to the end
  EXPECT_NE(r.output.find("/dev/full"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
}

TEST(WriteErrors, ReplayImuRateTrajectoryToAFullDisk) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto r = replay_with(*drive, [](ReplayOptions& o) { o.imu_rate_tum = "/dev/full"; });
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos) << r.output;
}

TEST(WriteErrors, ReplayScanLogToAFullDisk) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto r = replay_with(*drive, [](ReplayOptions& o) { o.scan_log_csv = "/dev/full"; });
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("/dev/full"), std::string::npos) << r.output;
}

// The command line as the review reproduced it: a summary, then a non-zero exit.
TEST(WriteErrors, LiodReplayCommandExitsNonZero) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  const auto bin = binary_dir() / "bin" / "liod";
  if (!std::filesystem::exists(bin)) GTEST_SKIP() << "liod binary not built";
  const ScratchDir dir("write-errors-cli");
  const std::string cmd = bin.string() + " replay --config " + LIOD_SOURCE_DIR + "/config/liod.yaml --config " +
                          (*drive / "extrinsics.yaml").string() + " --pcap " + (*drive / "lidar.pcap").string() +
                          " --imu " + (*drive / "imu.csv").string() + " --trajectory /dev/full --no-progress > " +
                          (dir / "out.txt").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = slurp(dir / "out.txt");
  ASSERT_TRUE(WIFEXITED(status)) << out;
  EXPECT_EQ(WEXITSTATUS(status), 1) << out;
  EXPECT_NE(out.find("replay: "), std::string::npos) << out;
}
