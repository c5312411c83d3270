#include "liod/fault/recording.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/pcap_writer.hpp"

namespace liod::fault {

Recording read_recording(const std::filesystem::path& pcap, const std::filesystem::path& imu_csv) {
  Recording r;
  drivers::PcapReader reader(pcap);
  drivers::UdpDatagram d;
  while (reader.next(d)) {
    r.packets.push_back(Packet{d.capture_time_ns, d.src_ip, d.dst_ip, d.src_port, d.dst_port,
                               std::vector<std::uint8_t>(d.payload.begin(), d.payload.end())});
  }
  r.imu = drivers::read_imu_csv(imu_csv);
  std::int64_t origin = std::numeric_limits<std::int64_t>::max();
  if (!r.packets.empty()) origin = r.packets.front().capture_time_ns;
  if (!r.imu.empty()) origin = std::min(origin, static_cast<std::int64_t>(std::llround(r.imu.front().time * 1e9)));
  r.origin_ns = origin == std::numeric_limits<std::int64_t>::max() ? 0 : origin;
  return r;
}

void write_recording(const Recording& recording, const std::filesystem::path& pcap, const std::filesystem::path& imu_csv) {
  drivers::PcapWriter writer(pcap);
  for (const Packet& p : recording.packets) {
    drivers::UdpDatagram d;
    d.capture_time_ns = p.capture_time_ns;
    d.src_ip = p.src_ip;
    d.dst_ip = p.dst_ip;
    d.src_port = p.src_port;
    d.dst_port = p.dst_port;
    d.payload = p.payload;
    writer.write(d);
  }
  writer.flush();
  drivers::ImuCsvWriter imu(imu_csv);
  for (const ImuSample& s : recording.imu) imu.write(s);
  imu.flush();
}

}  // namespace liod::fault
