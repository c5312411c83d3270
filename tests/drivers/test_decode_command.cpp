#include <gtest/gtest.h>

#include <sstream>

#include "liod/daemon/decode_command.hpp"
#include "liod/drivers/pcd_io.hpp"
#include "test_support.hpp"

namespace liod {
namespace {

TEST(DecodeCommand, DecodesTheReal16PCaptureIntoPcdFiles) {
  const auto pcap = drivers::test::robosense_dir() / "helios16p_5rev.pcap";
  LIOD_REQUIRE_SHARED(pcap);
  drivers::test::TempDir dir;
  DecodeOptions o;
  o.pcap = pcap.string();
  o.angles_csv = (drivers::test::robosense_dir() / "helios16p_angles.csv").string();
  o.out_dir = (dir / "out").string();
  std::ostringstream out;
  ASSERT_EQ(run_decode(o, out), 0) << out.str();
  const std::string text = out.str();
  EXPECT_NE(text.find("RS-Helios-16P"), std::string::npos) << text;  // inferred from 16 CSV rows
  EXPECT_NE(text.find("sweep 000004"), std::string::npos) << text;
  EXPECT_EQ(text.find("sweep 000005"), std::string::npos) << text;
  EXPECT_NE(text.find("rings 16/16"), std::string::npos) << text;
  EXPECT_NE(text.find("packets: msop 750, difop 1, rejected 0"), std::string::npos) << text;
  EXPECT_NE(text.find("truncated_file 0"), std::string::npos) << text;
  for (int i = 0; i < 5; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "sweep_%06d.pcd", i);
    EXPECT_TRUE(std::filesystem::exists(dir / "out" / name)) << name;
  }
  EXPECT_GT(drivers::read_pcd(dir / "out" / "sweep_000001.pcd").points(), 15000U);
}

TEST(DecodeCommand, ReportsErrorsWithNonZeroExit) {
  drivers::test::TempDir dir;
  std::ostringstream out;
  DecodeOptions o;
  o.pcap = (dir / "missing.pcap").string();
  EXPECT_EQ(run_decode(o, out), 1);
  EXPECT_NE(out.str().find("missing.pcap"), std::string::npos) << out.str();

  out.str("");
  o.pcap = "";
  EXPECT_EQ(run_decode(o, out), 2);

  out.str("");
  drivers::test::write_bytes(dir / "a.pcap", drivers::test::classic_pcap({}, 1));
  o.pcap = (dir / "a.pcap").string();
  o.model = "velodyne";
  EXPECT_EQ(run_decode(o, out), 2);
  EXPECT_NE(out.str().find("unknown model"), std::string::npos) << out.str();

  out.str("");
  o.model.clear();
  std::ofstream(dir / "bad.csv") << "1,2\nx,3\n";
  o.angles_csv = (dir / "bad.csv").string();
  EXPECT_EQ(run_decode(o, out), 1);
  EXPECT_NE(out.str().find("bad.csv:2"), std::string::npos) << out.str();
}

TEST(DecodeCommand, WithoutCalibrationItSaysSo) {
  drivers::test::TempDir dir;
  std::array<drivers::test::SyntheticBlock, 12> blocks{};
  std::vector<drivers::test::Record> records;
  records.push_back({1'000'000'000, drivers::test::udp_ethernet_frame(6699, drivers::test::make_msop(1'000'000, 1, blocks)), 0});
  drivers::test::write_bytes(dir / "nocal.pcap", drivers::test::classic_pcap(records, 1));
  DecodeOptions o;
  o.pcap = (dir / "nocal.pcap").string();
  std::ostringstream out;
  EXPECT_EQ(run_decode(o, out), 1);
  EXPECT_NE(out.str().find("pass --angles"), std::string::npos) << out.str();
}

}  // namespace
}  // namespace liod
