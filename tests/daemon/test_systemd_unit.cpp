// The service unit: `systemd-analyze verify` accepts it (where systemd is installed), it has the
// settings the service relies on, and its sandbox rates 2.0 or lower in `systemd-analyze security`.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "liod/config.hpp"
#include "test_support.hpp"

namespace {

std::string read_unit() {
  std::ifstream in(std::string(LIOD_SOURCE_DIR) + "/systemd/liod.service");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Whether `unit` has the line `line` exactly.
bool has_line(const std::string& unit, const std::string& line) {
  std::istringstream in(unit);
  std::string l;
  while (std::getline(in, l)) {
    if (l == line) return true;
  }
  return false;
}

/// The value of the directive `key` (the first `key=...` line), "" if none.
std::string value_of(const std::string& unit, const std::string& key) {
  std::istringstream in(unit);
  std::string l;
  while (std::getline(in, l)) {
    if (l.rfind(key + "=", 0) == 0) return l.substr(key.size() + 1);
  }
  return "";
}

}  // namespace

TEST(SystemdUnit, HasTheRequiredSettings) {
  const std::string unit = read_unit();
  ASSERT_FALSE(unit.empty());
  for (const char* key : {"Type=notify", "WatchdogSec=", "Restart=on-failure", "RuntimeDirectory=liod", "StateDirectory=liod",
                          "ProtectSystem=strict", "NoNewPrivileges=yes", "LimitRTPRIO=", "KillSignal=SIGTERM"}) {
    EXPECT_NE(unit.find(key), std::string::npos) << key;
  }
}

// What the sandbox holds: no capability (SCHED_FIFO comes from LimitRTPRIO, mlockall from
// LimitMEMLOCK), a system-call allow list, /proc limited to its own processes, and only the
// devices the IMU and PPS drivers open; real-time scheduling stays allowed.
TEST(SystemdUnit, SandboxKeepsWhatTheDaemonNeeds) {
  const std::string unit = read_unit();
  for (const char* line : {"CapabilityBoundingSet=", "LimitMEMLOCK=infinity", "SystemCallFilter=@system-service",
                           "SystemCallErrorNumber=EPERM", "SystemCallArchitectures=native", "ProtectProc=invisible",
                           "ProcSubset=pid", "DevicePolicy=closed", "DeviceAllow=char-ttyS rw", "DeviceAllow=char-ttyUSB rw",
                           "DeviceAllow=char-ttyACM rw", "DeviceAllow=char-gpiochip rw", "MemoryDenyWriteExecute=yes",
                           "RestrictAddressFamilies=AF_UNIX AF_INET AF_CAN AF_NETLINK", "ReadWritePaths=/var/lib/liod"}) {
    EXPECT_TRUE(has_line(unit, line)) << line;
  }
  std::istringstream lines(unit);
  for (std::string l; std::getline(lines, l);) {
    if (!l.empty() && l[0] != '#') {
      EXPECT_EQ(l.find("CAP_"), std::string::npos) << l;
    }
  }
  EXPECT_EQ(value_of(unit, "RestrictRealtime"), "") << "the driver and odometry threads run SCHED_FIFO";
  EXPECT_EQ(value_of(unit, "PrivateDevices"), "") << "it hides the serial ports";
  // Every configured SCHED_FIFO priority is within LimitRTPRIO (beyond it the thread would run
  // with normal scheduling: no capability raises it).
  const int rtprio = std::stoi(value_of(unit, "LimitRTPRIO"));
  const liod::Config config = liod::load_config({std::string(LIOD_SOURCE_DIR) + "/config/liod.yaml"});
  for (const auto* t : {&config.threads.lidar, &config.threads.imu, &config.threads.odometry, &config.threads.publisher}) {
    EXPECT_LE(t->priority, rtprio);
  }
  EXPECT_TRUE(config.threads.lock_memory);
}

// `systemd-analyze security` rates the unit's exposure 2.0 or lower.
TEST(SystemdUnit, SecurityExposureAtMostTwo) {
  LIOD_SKIP_UNLESS(std::system("command -v systemd-analyze >/dev/null 2>&1") == 0, "systemd-analyze not installed");
  const liod::test::ScratchDir dir("unit-security");
  const std::string cmd = "systemd-analyze security --offline=yes --no-pager " + std::string(LIOD_SOURCE_DIR) +
                          "/systemd/liod.service > " + (dir / "out.txt").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream o(dir / "out.txt");
  std::ostringstream out;
  out << o.rdbuf();
  const std::string text = out.str();
  const std::string key = "Overall exposure level for liod.service: ";
  const std::size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos) << "exit " << rc << "\n" << text;
  const double exposure = std::stod(text.substr(at + key.size()));
  std::printf("[ unit ] %s\n", text.substr(at, text.find('\n', at) - at).c_str());
  EXPECT_LE(exposure, 2.0) << text;
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
