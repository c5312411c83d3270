// The UDP LiDAR driver: the real RS-Helios-16P capture sent over loopback at recorded pace and at
// 5x arrives without loss and assembles into the same sweeps as decoding the file.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "liod/config.hpp"
#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"
#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/drivers/udp_receiver.hpp"
#include "test_support.hpp"
#include "udp_sender.hpp"

using namespace liod;

namespace {

struct SweepSummary {
  double start, end;
  std::size_t points;
  bool operator==(const SweepSummary&) const = default;
};

Config helios16p_config(std::uint16_t msop, std::uint16_t difop) {
  Config c;
  c.lidar.model = LidarModel::kHelios16P;
  c.lidar.angles_csv = (test::shared_dir() / "data/robosense/helios16p_angles.csv").string();
  c.lidar.msop_port = msop;
  c.lidar.difop_port = difop;
  c.drivers.lidar.bind_address = "127.0.0.1";
  c.time.lidar_clock = LidarClock::kSensor;  // the recording's sensor clock reads 2017
  c.threads.scan_ring = 64;
  return c;
}

/// The sweeps waiting in `ring`, in order.
std::vector<SweepSummary> drain(drivers::SpscRing<ScanItem>& ring) {
  std::vector<SweepSummary> sweeps;
  ScanItem s;
  while (ring.try_pop(s)) sweeps.push_back({s.scan.start_time, s.scan.end_time, s.scan.points.size()});
  return sweeps;
}

/// Once `out` has all `sent` datagrams: stops the driver thread and returns the sweeps it made.
std::vector<SweepSummary> finish_and_drain(LidarOutput& out, std::size_t sent, std::atomic<bool>& stop,
                                           std::thread& driver, drivers::SpscRing<ScanItem>& ring) {
  EXPECT_TRUE(test::wait_for([&] { return out.packets() >= sent; }, std::chrono::milliseconds(5000)));
  stop = true;
  driver.join();
  out.finish();
  return drain(ring);
}

/// The sweeps of the capture decoded from the file with the same settings: the reference.
std::vector<SweepSummary> file_sweeps(const Config& config, const std::filesystem::path& pcap) {
  drivers::SpscRing<ScanItem> ring(64);
  std::atomic<bool> stop{false};
  LidarOutput out(config, ring, true, false, stop);
  drivers::PcapReader reader(pcap);
  drivers::UdpDatagram d;
  while (reader.next(d)) out.packet(d.payload, d.capture_time_ns, d.dst_port);
  out.finish();
  return drain(ring);
}

const std::filesystem::path kHelios16pPcap = test::shared_dir() / "data/robosense/helios16p_5rev.pcap";

void udp_same_sweeps(double pace) {
  const auto& pcap = kHelios16pPcap;
  LIOD_REQUIRE_SHARED(pcap);
  const auto port = static_cast<std::uint16_t>(40000 + (::getpid() % 5000) * 4 + (pace > 1 ? 2 : 0));
  const Config config = helios16p_config(port, static_cast<std::uint16_t>(port + 1));
  const std::vector<SweepSummary> expected = file_sweeps(config, pcap);
  ASSERT_GE(expected.size(), 4U);

  drivers::SpscRing<ScanItem> ring(64);
  std::atomic<bool> stop{false};
  LidarOutput out(config, ring, false, true, stop);  // live, as liod run
  UdpLidarSource source(config);
  std::thread driver([&] { source.run(out, stop); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // sockets bound
  const std::size_t sent = test::send_pcap_loopback(pcap.string(), {{6699, port}, {7788, static_cast<std::uint16_t>(port + 1)}}, pace);
  const std::vector<SweepSummary> got = finish_and_drain(out, sent, stop, driver, ring);
  EXPECT_EQ(sent, 751U);  // 750 MSOP + 1 DIFOP
  EXPECT_EQ(out.packets(), sent);
  EXPECT_EQ(out.decoder_stats().lost_packets, 0U);
  EXPECT_EQ(ring.drops(), 0U);
  EXPECT_EQ(got, expected);
}

}  // namespace

TEST(UdpLidar, RealHeliosRecordedPaceNoLossSameSweeps) { udp_same_sweeps(1.0); }
TEST(UdpLidar, RealHeliosFiveTimesPaceNoLossSameSweeps) { udp_same_sweeps(5.0); }

namespace {

/// Sends each payload from `source` (a loopback address other than 127.0.0.1 is a second host) to
/// 127.0.0.1:`port`, `interval` apart. Returns how many were sent.
std::size_t send_from(const char* source, std::uint16_t port, const std::vector<std::vector<std::uint8_t>>& payloads,
                      std::chrono::microseconds interval) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in from{};
  from.sin_family = AF_INET;
  from.sin_addr.s_addr = htonl(drivers::parse_ipv4(source));
  if (fd < 0 || ::bind(fd, reinterpret_cast<const sockaddr*>(&from), sizeof from) != 0) return 0;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::size_t sent = 0;
  for (const auto& p : payloads) {
    if (::sendto(fd, p.data(), p.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) ==
        static_cast<ssize_t>(p.size()))
      ++sent;
    std::this_thread::sleep_for(interval);
  }
  ::close(fd);
  return sent;
}

}  // namespace

TEST(UdpLidar, ASecondSenderOnTheLidarPortIsDroppedAndCounted) {
  const auto& pcap = kHelios16pPcap;
  LIOD_REQUIRE_SHARED(pcap);
  const auto port = static_cast<std::uint16_t>(30000 + (::getpid() % 5000) * 2);
  const Config config = helios16p_config(port, static_cast<std::uint16_t>(port + 1));  // no source_address
  const std::vector<SweepSummary> expected = file_sweeps(config, pcap);
  ASSERT_GE(expected.size(), 4U);
  // The second host replays the capture's MSOP packets with every block at 100.00 deg.
  std::vector<std::vector<std::uint8_t>> foreign;
  {
    drivers::PcapReader reader(pcap);
    drivers::UdpDatagram d;
    while (reader.next(d) && foreign.size() < 300) {
      if (d.dst_port != 6699) continue;
      foreign.emplace_back(d.payload.begin(), d.payload.end());
      for (std::size_t b = 0; b < 12; ++b) drivers::store_be16(foreign.back().data() + 42 + 100 * b + 2, 10000);
    }
  }

  drivers::SpscRing<ScanItem> ring(64);
  std::atomic<bool> stop{false};
  LidarOutput out(config, ring, false, true, stop);  // live, as liod run
  UdpLidarSource source(config);
  std::thread driver([&] { source.run(out, stop); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // sockets bound
  std::size_t sent = 0;
  std::thread lidar([&] {
    sent = test::send_pcap_loopback(pcap.string(), {{6699, port}, {7788, static_cast<std::uint16_t>(port + 1)}}, 1.0);
  });
  ASSERT_TRUE(test::wait_for([&] { return out.packets() >= 1; }, std::chrono::milliseconds(2000)));
  const std::size_t foreign_sent = send_from("127.0.0.2", port, foreign, std::chrono::microseconds(1000));
  lidar.join();
  const std::vector<SweepSummary> got = finish_and_drain(out, sent, stop, driver, ring);
  EXPECT_EQ(foreign_sent, 300U);
  EXPECT_EQ(out.packets(), sent);  // the LiDAR's datagrams only
  EXPECT_EQ(out.transport.refused.load(), foreign_sent);
  EXPECT_EQ(got, expected);
}

TEST(UdpLidar, SourceAddressFilterDropsOtherSenders) {
  drivers::UdpReceiverOptions o;
  o.bind_address = "127.0.0.1";
  const auto port = static_cast<std::uint16_t>(45000 + ::getpid() % 5000);
  o.ports = {port};
  o.source_address = "127.0.0.2";  // the test sends from 127.0.0.1
  drivers::UdpReceiver receiver(o);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const char payload[4] = {1, 2, 3, 4};
  for (int i = 0; i < 3; ++i) ::sendto(fd, payload, 4, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  ::close(fd);
  std::size_t delivered = 0;
  for (int i = 0; i < 10; ++i) delivered += receiver.poll(20, [](const drivers::ReceivedDatagram&) {});
  EXPECT_EQ(delivered, 0U);
  EXPECT_EQ(receiver.stats().filtered_source, 3U);
}

TEST(UdpLidar, KernelTimestampsArePresent) {
  drivers::UdpReceiverOptions o;
  o.bind_address = "127.0.0.1";
  const auto port = static_cast<std::uint16_t>(46000 + ::getpid() % 5000);
  o.ports = {port};
  drivers::UdpReceiver receiver(o);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const auto before = drivers::realtime_ns();
  ::sendto(fd, "x", 1, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  ::close(fd);
  std::int64_t stamp = 0;
  for (int i = 0; i < 10 && stamp == 0; ++i) receiver.poll(20, [&](const drivers::ReceivedDatagram& d) { stamp = d.kernel_time_ns; });
  EXPECT_GE(stamp, before);
  EXPECT_LT(stamp - before, 1000000000);
}
