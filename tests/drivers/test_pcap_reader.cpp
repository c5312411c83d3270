#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

using test::Record;

struct Datagram {
  std::int64_t time_ns;
  std::uint32_t src_ip, dst_ip;
  std::uint16_t src_port, dst_port;
  std::vector<std::uint8_t> payload;
  bool operator==(const Datagram&) const = default;
};

std::vector<Datagram> read_all(PcapReader& reader) {
  std::vector<Datagram> out;
  UdpDatagram d;
  while (reader.next(d))
    out.push_back({d.capture_time_ns, d.src_ip, d.dst_ip, d.src_port, d.dst_port,
                   std::vector<std::uint8_t>(d.payload.begin(), d.payload.end())});
  return out;
}

std::vector<Datagram> read_all(const std::filesystem::path& path) {
  PcapReader reader(path);
  return read_all(reader);
}

std::vector<Record> ethernet_records(const std::vector<Datagram>& datagrams) {
  std::vector<Record> records;
  for (const Datagram& d : datagrams) records.push_back({d.time_ns, test::udp_ethernet_frame(d.dst_port, d.payload), 0});
  return records;
}

std::vector<Datagram> synthetic_datagrams(std::size_t n) {
  std::vector<Datagram> out;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<std::uint8_t> payload(100 + i);
    for (std::size_t j = 0; j < payload.size(); ++j) payload[j] = static_cast<std::uint8_t>(i * 7 + j);
    out.push_back({1'700'000'000'123'456'000LL + static_cast<std::int64_t>(i) * 1'000'000, 0xC0A801C8, 0xC0A80166,
                   static_cast<std::uint16_t>(i % 2 ? 7788 : 6699), static_cast<std::uint16_t>(i % 2 ? 7788 : 6699),
                   payload});
  }
  return out;
}

TEST(PcapReader, ReadsTheRealHelios16PCapture) {
  const auto path = test::robosense_dir() / "helios16p_5rev.pcap";
  LIOD_REQUIRE_SHARED(path);
  PcapReader reader(path);
  const auto all = read_all(reader);
  EXPECT_EQ(reader.format(), CaptureFormat::Pcap);
  EXPECT_TRUE(reader.error().empty());
  ASSERT_EQ(all.size(), 751U);
  EXPECT_EQ(reader.stats().records, 751U);
  EXPECT_EQ(reader.stats().dropped(), 0U);
  const auto msop = std::count_if(all.begin(), all.end(), [](const Datagram& d) { return d.dst_port == 6699; });
  EXPECT_EQ(msop, 750);
  for (const Datagram& d : all) EXPECT_EQ(d.payload.size(), 1248U);
  // First record: 1483724884.201573 s, 192.168.1.200 -> 192.168.1.102 (bytes checked with xxd).
  EXPECT_EQ(all[0].time_ns, 1483724884'201573000LL);
  EXPECT_EQ(all[0].src_ip, 0xC0A801C8U);
  EXPECT_EQ(all[0].dst_ip, 0xC0A80166U);
  EXPECT_EQ(all[543].dst_port, 7788);
}

TEST(PcapReader, PortFilterCountsWhatItSkips) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(10);
  test::write_bytes(dir / "a.pcap", test::classic_pcap(ethernet_records(data), 1));
  PcapReader reader(dir / "a.pcap");
  reader.set_port_filter({6699});
  const auto got = read_all(reader);
  EXPECT_EQ(got.size(), 5U);
  EXPECT_EQ(reader.stats().port_filtered, 5U);
  for (const auto& d : got) EXPECT_EQ(d.dst_port, 6699);
}

TEST(PcapReader, ClassicByteOrdersAndResolutionsAgree) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(6);
  const auto records = ethernet_records(data);
  for (bool nanos : {false, true}) {
    for (bool be : {false, true}) {
      const auto path = dir / ("v" + std::to_string(nanos) + std::to_string(be) + ".pcap");
      test::write_bytes(path, test::classic_pcap(records, 1, nanos, be));
      EXPECT_EQ(read_all(path), data) << "nanos=" << nanos << " big_endian=" << be;
    }
  }
}

TEST(PcapReader, PcapNgDecodesIdenticallyToClassic) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(7);
  for (bool be : {false, true}) {
    const auto path = dir / ("n" + std::to_string(be) + ".pcapng");
    test::write_bytes(path, test::pcapng(ethernet_records(data), 1, be));
    PcapReader reader(path);
    EXPECT_EQ(reader.format(), CaptureFormat::PcapNg);
    EXPECT_EQ(read_all(reader), data) << "big_endian=" << be;
  }
}

// Found by fuzz_pcap_reader: an if_tsresol of 2^-127 s (any exponent past 93) shifted a 64-bit
// value by 64 or more bits, which is undefined behaviour. Such units are all below a nanosecond.
TEST(PcapReader, PcapNgFinestPowerOfTwoResolutionIsDefined) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(3);
  for (const int resolution : {0x80 | 94, 0x80 | 127}) {
    auto bytes = test::pcapng(ethernet_records(data), 1);
    bytes[28 + 20] = static_cast<std::uint8_t>(resolution);  // the IDB's if_tsresol value: SHB (28 bytes), IDB header (16), option header (4)
    test::write_bytes(dir / "fine.pcapng", bytes);
    const auto got = read_all(dir / "fine.pcapng");
    ASSERT_EQ(got.size(), data.size());
    for (const Datagram& d : got) EXPECT_EQ(d.time_ns, 0) << "if_tsresol 0x" << std::hex << resolution;
  }
}

TEST(PcapReader, VlanSllSll2AndRawIpFramesYieldTheSameDatagrams) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(5);
  const auto eth = ethernet_records(data);
  auto rewrap = [&](auto&& make) {
    std::vector<Record> out;
    for (const Record& r : eth) {
      const std::vector<std::uint8_t> ip(r.frame.begin() + 14, r.frame.end());
      out.push_back({r.time_ns, make(r.frame, ip), 0});
    }
    return out;
  };
  const auto vlan = rewrap([](const std::vector<std::uint8_t>& frame, const std::vector<std::uint8_t>&) {
    std::vector<std::uint8_t> f(frame.begin(), frame.begin() + 12);
    f.insert(f.end(), {0x81, 0x00, 0x00, 0x05});  // 802.1Q, VLAN 5
    f.insert(f.end(), frame.begin() + 12, frame.end());
    return f;
  });
  const auto qinq = rewrap([](const std::vector<std::uint8_t>& frame, const std::vector<std::uint8_t>&) {
    std::vector<std::uint8_t> f(frame.begin(), frame.begin() + 12);
    f.insert(f.end(), {0x88, 0xA8, 0x00, 0x07, 0x81, 0x00, 0x00, 0x05});  // 802.1ad outer + 802.1Q inner
    f.insert(f.end(), frame.begin() + 12, frame.end());
    return f;
  });
  const auto sll = rewrap([](const std::vector<std::uint8_t>&, const std::vector<std::uint8_t>& ip) {
    std::vector<std::uint8_t> f = {0x00, 0x00, 0x00, 0x01, 0x00, 0x06, 1, 2, 3, 4, 5, 6, 0, 0, 0x08, 0x00};
    f.insert(f.end(), ip.begin(), ip.end());
    return f;
  });
  const auto sll2 = rewrap([](const std::vector<std::uint8_t>&, const std::vector<std::uint8_t>& ip) {
    std::vector<std::uint8_t> f = {0x08, 0x00, 0, 0, 0, 0, 0, 2, 0x00, 0x01, 0x00, 6, 1, 2, 3, 4, 5, 6, 0, 0};
    f.insert(f.end(), ip.begin(), ip.end());
    return f;
  });
  const auto raw = rewrap([](const std::vector<std::uint8_t>&, const std::vector<std::uint8_t>& ip) { return ip; });

  const struct {
    const char* name;
    const std::vector<Record>* records;
    std::uint32_t link;
  } cases[] = {{"vlan", &vlan, 1}, {"qinq", &qinq, 1}, {"sll", &sll, 113}, {"sll2", &sll2, 276}, {"raw", &raw, 101}};
  for (const auto& c : cases) {
    const auto path = dir / (std::string(c.name) + ".pcap");
    test::write_bytes(path, test::classic_pcap(*c.records, c.link));
    EXPECT_EQ(read_all(path), data) << c.name;
    const auto ng = dir / (std::string(c.name) + ".pcapng");
    test::write_bytes(ng, test::pcapng(*c.records, c.link));
    EXPECT_EQ(read_all(ng), data) << c.name << " (pcapng)";
  }
}

TEST(PcapReader, CountsFragmentsNonUdpNonIpv4AndSnaplenCuts) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(8);
  auto records = ethernet_records(data);
  records[1].frame[14 + 6] |= 0x20;                       // IPv4 "more fragments"
  records[2].frame[14 + 7] = 0x10;                        // fragment offset != 0
  records[3].frame[14 + 9] = 6;                           // TCP
  records[4].frame[12] = 0x08;                            // ARP ethertype
  records[4].frame[13] = 0x06;
  records[5].orig_len = static_cast<std::uint32_t>(records[5].frame.size() + 100);  // caplen < len
  records[6].frame.resize(30);                            // IP header claims more than captured
  records[6].orig_len = 30;
  test::write_bytes(dir / "bad.pcap", test::classic_pcap(records, 1));
  PcapReader reader(dir / "bad.pcap");
  const auto got = read_all(reader);
  ASSERT_EQ(got.size(), 2U);
  EXPECT_EQ(got[0], data[0]);
  EXPECT_EQ(got[1], data[7]);
  const PcapStats& s = reader.stats();
  EXPECT_EQ(s.records, 8U);
  EXPECT_EQ(s.ip_fragment, 2U);
  EXPECT_EQ(s.not_udp, 1U);
  EXPECT_EQ(s.not_ipv4, 1U);
  EXPECT_EQ(s.truncated_record, 1U);
  EXPECT_EQ(s.malformed, 1U);
  EXPECT_EQ(s.dropped(), 6U);
  EXPECT_TRUE(reader.error().empty());
}

TEST(PcapReader, FileCutMidRecordYieldsTheGoodRecordsAndReportsTheCut) {
  const auto path = test::robosense_dir() / "helios16p_5rev.pcap";
  LIOD_REQUIRE_SHARED(path);
  const auto bytes = test::read_bytes(path);
  test::TempDir dir;
  // 24-byte header, then 16 + 1290 bytes per record: cut inside record 100's data, then inside a
  // record header.
  const std::size_t record = 16 + 1290;
  for (const std::size_t cut : {24 + 100 * record + 700, 24 + 100 * record + 9}) {
    std::vector<std::uint8_t> part(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut));
    test::write_bytes(dir / "cut.pcap", part);
    PcapReader reader(dir / "cut.pcap");
    const auto got = read_all(reader);
    EXPECT_EQ(got.size(), 100U) << "cut at " << cut;
    EXPECT_EQ(reader.stats().truncated_file, 1U);
    EXPECT_NE(reader.error().find("file ends inside a record"), std::string::npos) << reader.error();
    EXPECT_NE(reader.error().find("cut.pcap"), std::string::npos) << reader.error();
    UdpDatagram d;
    EXPECT_FALSE(reader.next(d));  // stays at the end
  }
}

TEST(PcapReader, PcapNgCutMidBlockIsReported) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(4);
  auto bytes = test::pcapng(ethernet_records(data), 1);
  bytes.resize(bytes.size() - 10);
  test::write_bytes(dir / "cut.pcapng", bytes);
  PcapReader reader(dir / "cut.pcapng");
  EXPECT_EQ(read_all(reader).size(), 3U);
  EXPECT_EQ(reader.stats().truncated_file, 1U);
  EXPECT_FALSE(reader.error().empty());
}

TEST(PcapReader, GarbageHeaderThrowsNamingTheFile) {
  test::TempDir dir;
  test::write_bytes(dir / "garbage.pcap", std::vector<std::uint8_t>(64, 0x42));
  try {
    PcapReader reader(dir / "garbage.pcap");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("garbage.pcap"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a pcap or pcapng"), std::string::npos) << e.what();
  }
  test::write_bytes(dir / "short.pcap", {0xD4, 0xC3});
  EXPECT_THROW(PcapReader(dir / "short.pcap"), InputError);
  EXPECT_THROW(PcapReader(dir / "missing.pcap"), InputError);
  // Valid magic, unsupported link type (IEEE 802.11 = 105).
  test::write_bytes(dir / "wifi.pcap", test::classic_pcap({}, 105));
  EXPECT_THROW(PcapReader(dir / "wifi.pcap"), InputError);
}

TEST(PcapReader, CorruptRecordLengthStopsWithoutHugeAllocation) {
  test::TempDir dir;
  auto bytes = test::classic_pcap(ethernet_records(synthetic_datagrams(3)), 1);
  // Second record's caplen: 24 + 16 + frame0 size + 8.
  const std::size_t frame0 = test::udp_ethernet_frame(6699, std::vector<std::uint8_t>(100)).size();
  store_le32(bytes.data() + 24 + 16 + frame0 + 8, 0x7FFFFFF0);
  test::write_bytes(dir / "corrupt.pcap", bytes);
  PcapReader reader(dir / "corrupt.pcap");
  EXPECT_EQ(read_all(reader).size(), 1U);
  EXPECT_NE(reader.error().find("corrupt record header"), std::string::npos) << reader.error();
}

// Found by fuzz_pcap_reader: a file header claiming a huge snaplen lifted that limit, so a corrupt
// record length had the reader allocate and zero-fill up to 4 GiB before its read came up short.
TEST(PcapReader, HugeSnaplenDoesNotLiftTheRecordLengthLimit) {
  test::TempDir dir;
  auto bytes = test::classic_pcap(ethernet_records(synthetic_datagrams(3)), 1);
  store_le32(bytes.data() + 16, 0xFFFFFFFF);  // snaplen
  const std::size_t frame0 = test::udp_ethernet_frame(6699, std::vector<std::uint8_t>(100)).size();
  store_le32(bytes.data() + 24 + 16 + frame0 + 8, 587'323'939);  // the fuzzer's captured length
  test::write_bytes(dir / "corrupt.pcap", bytes);
  PcapReader reader(dir / "corrupt.pcap");
  EXPECT_EQ(read_all(reader).size(), 1U);
  EXPECT_NE(reader.error().find("corrupt record header"), std::string::npos) << reader.error();
  EXPECT_EQ(reader.stats().malformed, 1U);
}

TEST(PcapReader, RandomCorruptionNeverCrashes) {
  // Flip random bytes of valid pcap and pcapng files and cut them at random lengths: the reader
  // must either refuse the file at open (InputError) or read to an orderly end.
  test::TempDir dir;
  const auto records = ethernet_records(synthetic_datagrams(12));
  const std::vector<std::uint8_t> originals[] = {test::classic_pcap(records, 1), test::pcapng(records, 1),
                                                 test::pcapng(records, 1, true)};
  std::mt19937 rng(7);
  for (int trial = 0; trial < 600; ++trial) {
    std::vector<std::uint8_t> bytes = originals[trial % 3];
    std::uniform_int_distribution<std::size_t> pos(0, bytes.size() - 1);
    const int flips = 1 + trial % 8;
    for (int f = 0; f < flips; ++f) bytes[pos(rng)] = static_cast<std::uint8_t>(rng());
    if (trial % 4 == 0) bytes.resize(pos(rng));
    test::write_bytes(dir / "fuzz", bytes);
    try {
      PcapReader reader(dir / "fuzz");
      UdpDatagram d;
      std::size_t n = 0;
      while (reader.next(d)) {
        ASSERT_LE(d.payload.size(), 65535U);
        ++n;
      }
      EXPECT_LE(n, 12U);
    } catch (const InputError&) {
    }
  }
}

TEST(PcapWriter, RoundTripsThroughTheReader) {
  test::TempDir dir;
  const auto data = synthetic_datagrams(5);
  {
    PcapWriter writer(dir / "w.pcap");
    for (const Datagram& d : data) {
      UdpDatagram u{d.time_ns, d.src_ip, d.dst_ip, d.src_port, d.dst_port, d.payload};
      writer.write(u);
    }
  }
  EXPECT_EQ(read_all(dir / "w.pcap"), data);
}

}  // namespace
}  // namespace liod::drivers
