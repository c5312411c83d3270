// The service unit: `systemd-analyze verify` accepts it (where systemd is installed) and it has
// the settings the service relies on.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "test_support.hpp"

TEST(SystemdUnit, HasTheRequiredSettings) {
  std::ifstream in(std::string(LIOD_SOURCE_DIR) + "/systemd/liod.service");
  ASSERT_TRUE(in);
  std::ostringstream s;
  s << in.rdbuf();
  const std::string unit = s.str();
  for (const char* key : {"Type=notify", "WatchdogSec=", "Restart=on-failure", "RuntimeDirectory=liod", "StateDirectory=liod",
                          "ProtectSystem=strict", "NoNewPrivileges=yes", "CapabilityBoundingSet=CAP_SYS_NICE",
                          "AmbientCapabilities=CAP_SYS_NICE", "LimitRTPRIO=", "KillSignal=SIGTERM"}) {
    EXPECT_NE(unit.find(key), std::string::npos) << key;
  }
}

TEST(SystemdUnit, SystemdAnalyzeVerify) {
  LIOD_SKIP_UNLESS(std::system("command -v systemd-analyze >/dev/null 2>&1") == 0, "systemd-analyze not installed");
  LIOD_REQUIRE_PROGRAM("liod");
  // The unit names /usr/bin/liod; verify checks that ExecStart's binary exists, so verify a copy
  // pointing at the build tree's binary.
  const liod::test::ScratchDir dir("unit");
  std::ifstream in(std::string(LIOD_SOURCE_DIR) + "/systemd/liod.service");
  std::ostringstream s;
  s << in.rdbuf();
  std::string unit = s.str();
  const std::string bin = std::string(LIOD_BINARY_DIR) + "/bin/liod";
  for (std::size_t p; (p = unit.find("/usr/bin/liod")) != std::string::npos;) unit.replace(p, 13, bin);
  std::ofstream(dir / "liod.service") << unit;
  const std::string cmd = "systemd-analyze verify " + (dir / "liod.service").string() + " > " + (dir / "out.txt").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream o(dir / "out.txt");
  std::ostringstream out;
  out << o.rdbuf();
  EXPECT_EQ(rc, 0) << out.str();
}
