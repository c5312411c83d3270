// liod-fuzz-seeds OUT_DIR: writes the seed corpus of every fuzz target to OUT_DIR/<target>/.
// Sources: the liod-sim captures and IMU log cut into fuzz/corpus/, the project's configuration
// files, messages built with the project's own encoders, and, when ../shared is there, the real
// RS-Helios-16P recording and the two real angle tables (read in place, never copied into the
// project).
//
// fuzz/corpus/ holds, from `liod-sim --route urban --seed 7 --duration 1.2 [--dual-return]`: the
// DIFOP and the 4 MSOP packets around the first azimuth wrap after it (sim-5515-{single,dual}.pcap)
// and the first 12 samples of imu.csv (sim-imu.csv).

#include <linux/can.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "liod/daemon/pose_protocol.hpp"
#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/can_imu.hpp"
#include "liod/drivers/mtdata2.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios_difop.hpp"
#include "bag_writer.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace liod::drivers;
using Bytes = std::vector<std::uint8_t>;

const fs::path kSource = LIOD_SOURCE_DIR;
const fs::path kRealPcap = fs::path(LIOD_SHARED_DIR) / "data" / "robosense" / "helios16p_5rev.pcap";

class SeedWriter {
 public:
  explicit SeedWriter(fs::path root) : root_(std::move(root)) {}
  void write(const std::string& target, const std::string& name, const Bytes& bytes) {
    fs::create_directories(root_ / target);
    test::write_bytes(root_ / target / name, bytes);
    ++count_;
  }
  void write(const std::string& target, const std::string& name, const std::string& text) {
    write(target, name, Bytes(text.begin(), text.end()));
  }
  [[nodiscard]] int count() const { return count_; }

 private:
  fs::path root_;
  int count_ = 0;
};

struct Packet {
  std::uint16_t dst_port = 0;
  std::int64_t time_ns = 0;
  Bytes payload;
};

std::vector<Packet> read_packets(const fs::path& pcap) {
  std::vector<Packet> out;
  PcapReader reader(pcap);
  UdpDatagram d;
  while (reader.next(d)) out.push_back({d.dst_port, d.capture_time_ns, Bytes(d.payload.begin(), d.payload.end())});
  return out;
}

std::vector<test::Record> records(const std::vector<Packet>& packets) {
  std::vector<test::Record> r;
  for (const Packet& p : packets) r.push_back({p.time_ns, test::udp_ethernet_frame(p.dst_port, p.payload), 0});
  return r;
}

// ---- fuzz_rs_helios: prologue (see fuzz_rs_helios.cpp) + payloads --------------------------------
enum Flags : std::uint8_t { k16P = 1, kForceDual = 4, kFollow = 6, kDifopAngles = 8, kTableAngles = 16, kArrivalTime = 32 };

/// The split-azimuth byte that puts the sweep split inside `payload`'s block azimuths.
std::uint8_t split_inside(const Bytes& msop) {
  const double deg = load_be16(msop.data() + helios::kHeaderBytes + 2) * 0.01;
  return static_cast<std::uint8_t>(static_cast<int>(std::ceil(deg / (360.0 / 128.0))) & 0x7F);
}

Bytes helios_stream(std::uint8_t flags, std::uint8_t split, std::int64_t arrival_ns, const std::vector<Packet>& packets) {
  Bytes b{flags, split};
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(arrival_ns) >> (8 * i)));
  for (const Packet& p : packets) b.insert(b.end(), p.payload.begin(), p.payload.end());
  return b;
}

void capture_seeds(SeedWriter& out, const std::string& name, const std::vector<Packet>& packets, bool model_16p) {
  std::vector<Packet> difop_first;
  std::vector<Packet> msop_only;
  for (const Packet& p : packets) {
    if (has_difop_magic(p.payload)) difop_first.insert(difop_first.begin(), p);
    else if (msop_only.size() < 6) msop_only.push_back(p);
  }
  for (const Packet& p : msop_only) {
    if (difop_first.size() < 7) difop_first.push_back(p);
  }
  const std::uint8_t model = model_16p ? k16P : 0;
  const std::uint8_t split = split_inside(msop_only.at(msop_only.size() / 2).payload);
  const std::int64_t arrival = msop_only.front().time_ns;
  out.write("fuzz_rs_helios", name + "-difop-first", helios_stream(model | kDifopAngles, split, arrival, difop_first));
  if (has_difop_magic(difop_first.front().payload)) {
    // The CSV's table, the DIFOP's from the next sweep boundary, then another DIFOP whose first
    // elevation differs, followed at the boundary after (calibration_updates: follow).
    std::vector<Packet> difop_mid = msop_only;
    Packet changed = difop_first.front();
    changed.payload[468 + 2] ^= 0x10;
    difop_mid.insert(difop_mid.begin() + 4, changed);
    difop_mid.insert(difop_mid.begin() + 2, difop_first.front());
    out.write("fuzz_rs_helios", name + "-difops-mid-sweep-follow",
              helios_stream(model | kFollow | kDifopAngles | kTableAngles, split, arrival, difop_mid));
  }
  out.write("fuzz_rs_helios", name + "-table-arrival-time",
            helios_stream(model | kTableAngles | kArrivalTime, split | 0x80, arrival, msop_only));
  // Arrival times that leave the decoder's time range in mid-stream.
  constexpr auto kLastArrivalNs = static_cast<std::int64_t>(helios::kMaxTimestampSeconds) * 1'000'000'000LL;
  out.write("fuzz_rs_helios", name + "-arrival-time-limit",
            helios_stream(model | kTableAngles | kArrivalTime, split, kLastArrivalNs - 1'000'000, msop_only));
  if (!model_16p)
    out.write("fuzz_rs_helios", name + "-forced-dual", helios_stream(kForceDual | kTableAngles, 0, arrival, msop_only));

  const auto r = records(difop_first);
  out.write("fuzz_pcap_reader", name + "-us.pcap", test::classic_pcap(r, 1));
  out.write("fuzz_pcap_reader", name + "-ns-be.pcap", test::classic_pcap(r, 1, true, true));
  out.write("fuzz_pcap_reader", name + ".pcapng", test::pcapng(r, 1));
  out.write("fuzz_pcap_reader", name + "-be.pcapng", test::pcapng(r, 1, true));
}

// ---- fuzz_mtdata2 ---------------------------------------------------------------------------------

void mtdata2_seeds(SeedWriter& out) {
  Bytes stream;
  for (std::uint16_t k = 0; k < 3; ++k) {
    const Bytes m = xsens::build_mtdata2(k, 1000U * k, Eigen::Vector3d(0.01, -0.02, 0.03 * k),
                                         Eigen::Vector3d(0.1, 0.2, 9.81));
    stream.insert(stream.end(), m.begin(), m.end());
  }
  out.write("fuzz_mtdata2", "three-samples", stream);

  // Garbage, an acknowledgement (another MID), a FreeAcceleration item and a counter gap.
  Bytes mixed{0x00, xsens::kPreamble, 0x12, 0x34};
  const Bytes ack = xsens::build_xbus_message(0x3F, {});
  mixed.insert(mixed.end(), ack.begin(), ack.end());
  Bytes data = xsens::build_mtdata2(7, 70000, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81));
  data = Bytes(data.begin() + 4, data.end() - 1);  // the items alone
  data.insert(data.end(), {0x40, 0x30, 12});
  data.insert(data.end(), 12, 0);
  const Bytes with_free = xsens::build_xbus_message(xsens::kMidMtData2, data);
  mixed.insert(mixed.end(), with_free.begin(), with_free.end());
  out.write("fuzz_mtdata2", "garbage-ack-free-acceleration", mixed);

  // Extended length: the same items plus an unknown 250-byte item.
  data.insert(data.end(), {0x70, 0x10, 250});
  data.insert(data.end(), 250, 0xAB);
  out.write("fuzz_mtdata2", "extended-length", xsens::build_xbus_message(xsens::kMidMtData2, data));
}

// ---- fuzz_can_imu: struct can_frame + 2-byte µs delta --------------------------------------------
void put_frame(Bytes& out, const CanFrame& f, std::uint16_t delta_us) {
  can_frame raw{};
  raw.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0U);
  raw.can_dlc = f.dlc;
  std::memcpy(raw.data, f.data.data(), 8);
  const auto* p = reinterpret_cast<const std::uint8_t*>(&raw);
  out.insert(out.end(), p, p + sizeof raw);
  out.push_back(static_cast<std::uint8_t>(delta_us));
  out.push_back(static_cast<std::uint8_t>(delta_us >> 8));
}

void can_seeds(SeedWriter& out) {
  Bytes j1939;
  for (int k = 0; k < 3; ++k) {
    put_frame(j1939, make_j1939_accel_frame(Eigen::Vector3d(0.1, -0.2, 9.81), 0x80, 0), 4000);
    put_frame(j1939, make_j1939_rate_frame(Eigen::Vector3d(0.01, 0.02, -0.03 * k), 0x80, 0), 1000);
  }
  out.write("fuzz_can_imu", "j1939-pairs", j1939);

  // The fuzz target's table: accelerations on 0x101, rates (completing the sample) on 0x100.
  Bytes table;
  CanFrame accel;
  accel.id = 0x101;
  accel.dlc = 8;
  accel.data = {0x05, 0x10, 0x20, 0x30, 0x00, 0x7F, 0x00, 0x00};
  CanFrame rate;
  rate.id = 0x100;
  rate.dlc = 8;
  rate.data = {0x10, 0x00, 0xFF, 0xF0, 0x00, 0x00, 0x01, 0x00};
  put_frame(table, accel, 0);
  put_frame(table, rate, 500);
  out.write("fuzz_can_imu", "table-pair", table);
}

// ---- fuzz_time_sync: prologue + (op, int64, int64) records ----------------------------------------
void put_reading(Bytes& out, std::uint8_t op, std::int64_t a, std::int64_t b) {
  out.push_back(op);
  for (const std::int64_t v : {a, b}) {
    for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  }
}

void time_sync_seeds(SeedWriter& out) {
  // A LiDAR 0.5 s behind the host with up to 2 ms of delay, stepping 1 s at the 20th packet;
  // window 2^31 ns (2.1 s), threshold 2^27 ns (0.13 s), confirm 3; bridge threshold 2^27 ns.
  constexpr std::int64_t kHost = 1'700'000'000'000'000'000;
  Bytes tracker{31, 27, 2, 27, 0};
  for (std::int64_t k = 0; k < 40; ++k) {
    const std::int64_t header = kHost - 500'000'000 + k * 666'667 + (k >= 20 ? 1'000'000'000 : 0);
    put_reading(tracker, 0, kHost + k * 666'667 + (k % 7) * 300'000, header);
    put_reading(tracker, 1, header, k * 666'667);
  }
  out.write("fuzz_time_sync", "lidar-offset-and-step", tracker);
  Bytes pps{31, 27, 2, 27, 0};
  for (std::int64_t k = 0; k < 4; ++k) put_reading(pps, 2, kHost + k * 1'000'000'000 + 12'345, 0);
  put_reading(pps, 2, kHost + 450'000'000, 0);  // between seconds: no edge
  out.write("fuzz_time_sync", "pps-edges", pps);
}

// ---- fuzz_pose_socket -----------------------------------------------------------------------------
void pose_seeds(SeedWriter& out) {
  out.write("fuzz_pose_socket", "requests", std::string("json\nscan\r\nbinary \nall\n"));
  out.write("fuzz_pose_socket", "split-request", std::string("unknown\njs") + std::string("on\n"));
  liod::pose::PoseMessage m;
  m.type = liod::pose::MessageType::ImuPose;
  m.sequence = 42;
  m.time = 1700000000.25;
  m.position = Eigen::Vector3d(1, 2, 3);
  m.covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-4;
  m.flags = liod::pose::kOk | liod::pose::kKeyframe;
  Bytes stream;
  liod::pose::encode(m, stream);
  liod::pose::encode_health(R"({"state":"ok","socket":{"clients":1}})", 43, stream);
  out.write("fuzz_pose_socket", "pose-and-health", stream);
}

// ---- text inputs ----------------------------------------------------------------------------------
std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void text_seeds(SeedWriter& out) {
  for (const char* f : {"liod.yaml", "examples/slam.yaml", "vehicles/liod-sim-car.yaml"})
    out.write("fuzz_config", fs::path(f).filename().string(), read_text(kSource / "config" / f));
  out.write("fuzz_config", "can-table.yaml",
            std::string("drivers:\n  imu:\n    transport: can\n    can_profile: table\n    can_signals:\n"
                        "      - {quantity: gyro_x, id: 0x123, id_mask: 0x7FF, byte: 4, bytes: 2, endian: big,"
                        " signed: true, scale: 0.0001, offset: 0.0}\n"));

  const std::string imu = read_text(kSource / "fuzz" / "corpus" / "sim-imu.csv");
  out.write("fuzz_imu_csv", "sim-imu.csv", imu);
  out.write("fuzz_angles_csv", "comments-tabs-crlf.csv",
            std::string("# vertical_deg, horizontal_deg\r\n 14.94,\t-4.07\r\n\r\n13.03 , 3.63\r\n-54.6,4.8\n"));
  // Layout byte, then records: a KITTI-like sweep (x, y, z, reflectance) and a timed one.
  Bytes kitti{0};
  Bytes timed{1};
  for (int k = 0; k < 8; ++k) {
    const float az = 0.8F * static_cast<float>(k);
    const float record[5] = {20.0F * std::cos(az), 20.0F * std::sin(az), -0.7F * static_cast<float>(k % 4), 0.5F,
                             0.0125F * static_cast<float>(k)};
    for (int f = 0; f < 5; ++f) {
      std::uint8_t le[4];
      store_le32(le, std::bit_cast<std::uint32_t>(record[f]));
      if (f < 4) kitti.insert(kitti.end(), le, le + 4);
      timed.insert(timed.end(), le, le + 4);
    }
  }
  out.write("fuzz_point_records", "kitti-8.bin", kitti);
  out.write("fuzz_point_records", "timed-8.bin", timed);
  out.write("fuzz_kitti_text", "timestamp.txt", std::string("\0" "2011-09-26 13:02:25.964389445\n", 31));
  out.write("fuzz_kitti_text", "oxts.txt",
            std::string("\1" "49.015003823272 8.4342971002335 116.43032836914 0.035752 0.00903 -2.6087069803847 "
                        "-7.2145002546941 -3.4935373500311 8.0158904054762 0.012615712452997 0.18109542932771 "
                        "-0.21098555664 0.9315014834332 9.7843327712 -0.064806587567 0.93176174283 9.7874117565 "
                        "0.014236 -0.024386 0.018234 0.014722 -0.0241 0.018329 0.86210643005753 0.22090013123015 "
                        "4 11 6 6 6\n"));
  out.write("fuzz_imu_csv", "comments-crlf.csv",
            std::string("# IMU log\r\n time_s , gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\r\n\r\n"
                        "1.0,+0.1,-2e-3,0,0.0,0.0,9.81\r\n1.0,0,0,0,0,0,9.8\r\n"));
}

}  // namespace

// ---- fuzz_pipeline: model byte + records (see fuzz_pipeline.cpp) ---------------------------------
// A tiny synthetic drive at rest: sweeps of six copies of one simulated MSOP packet, their blocks'
// azimuths rewritten to six 60-degree steps, with a level IMU at rest sampled every 5 ms between
// them. A few thousand points a sweep keep a run of several sweeps to milliseconds.
void put_imu(Bytes& out, std::uint8_t step, const std::array<std::int16_t, 6>& axes) {
  out.push_back(0);
  out.push_back(step);
  for (const std::int16_t v : axes) {
    out.push_back(static_cast<std::uint8_t>(v & 0xFF));
    out.push_back(static_cast<std::uint8_t>((v >> 8) & 0xFF));
  }
}

Bytes tiny_drive(const Bytes& msop, int sweeps, std::int16_t gyro_z) {
  Bytes b{0};
  const std::array<std::int16_t, 6> at_rest{0, 0, gyro_z, 0, 0, 2452};  // 9.81 m/s^2 in 4e-3 units
  for (int i = 0; i < 20; ++i) put_imu(b, 9, at_rest);  // 0.1 s of IMU before the first packet
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (int k = 0; k < 6; ++k) {
      Bytes packet = msop;
      for (std::size_t block = 0; block < helios::kBlocksPerPacket; ++block) {
        const auto azimuth = static_cast<std::uint16_t>(k * 6000 + static_cast<int>(block) * 20);
        std::uint8_t* at = packet.data() + helios::kHeaderBytes + block * helios::kBlockBytes + 2;
        at[0] = static_cast<std::uint8_t>(azimuth >> 8);
        at[1] = static_cast<std::uint8_t>(azimuth & 0xFF);
      }
      b.push_back(1);
      b.push_back(1);
      b.insert(b.end(), packet.begin(), packet.end());
      for (int i = 0; i < 3; ++i) put_imu(b, 9, at_rest);  // 16 ms to the next packet
    }
  }
  for (int i = 0; i < 4; ++i) put_imu(b, 9, at_rest);
  return b;
}

void pipeline_seeds(SeedWriter& out) {
  Bytes msop;
  for (const Packet& p : read_packets(kSource / "fuzz" / "corpus" / "sim-5515-single.pcap")) {
    if (!has_difop_magic(p.payload)) {
      msop = p.payload;
      break;
    }
  }
  if (msop.size() != helios::kPacketBytes) throw std::runtime_error("no MSOP packet in sim-5515-single.pcap");
  out.write("fuzz_pipeline", "tiny-sweeps-at-rest", tiny_drive(msop, 5, 0));
  out.write("fuzz_pipeline", "tiny-sweeps-turning", tiny_drive(msop, 5, 200));
}

/// Small bags and MCAP files of two 16-point sweeps and a few IMU samples: every chunk codec,
/// the drivers' point layouts, ROS 1 serialization and CDR of both byte orders.
void bag_seeds(SeedWriter& out) {
  namespace bw = liod::test;
  liod::Scan scan;
  for (int k = 0; k < 8; ++k) {
    for (std::uint16_t r = 0; r < 2; ++r) {
      liod::LidarPoint p;
      p.x = static_cast<float>(5.0 * std::cos(k * 0.785));
      p.y = static_cast<float>(5.0 * std::sin(k * 0.785));
      p.z = r - 0.5F;
      p.ring = r;
      p.time = 0.0125F * static_cast<float>(k);
      scan.points.push_back(p);
    }
  }
  const std::vector<bw::TopicSpec> topics{{"/points", "sensor_msgs/PointCloud2"}, {"/imu", "sensor_msgs/Imu"}};
  auto messages = [&](bw::CloudLayout layout, bw::Serialization s) {
    std::vector<bw::MessageSpec> m;
    for (int i = 0; i < 6; ++i) {
      const double t = 1.7e9 + 0.05 * i;
      if (i % 3 == 0) m.push_back({0, bw::Stamp::of(t + 0.1).ns(), bw::serialize_cloud(scan, bw::Stamp::of(t), {layout, s})});
      liod::ImuSample imu;
      imu.time = t;
      imu.accel = Eigen::Vector3d(0.1, 0.0, 9.81);
      m.push_back({1, bw::Stamp::of(t).ns(), bw::serialize_imu(imu, s)});
    }
    return m;
  };
  const auto ros1 = messages(bw::CloudLayout::Velodyne, bw::Serialization::Ros1);
  for (const char* codec : {"none", "bz2", "lz4"}) {
    out.write("fuzz_ros_bag", std::string("velodyne-") + codec, bw::write_ros1_bag(topics, ros1, {codec, 400}));
  }
  out.write("fuzz_ros_bag", "hesai-unindexed", bw::write_ros1_bag(topics, messages(bw::CloudLayout::Hesai, bw::Serialization::Ros1), {"none", 400, false}));
  out.write("fuzz_mcap", "ouster-le", bw::write_mcap(topics, messages(bw::CloudLayout::Ouster, bw::Serialization::CdrLittle), {"", 400}));
  out.write("fuzz_mcap", "livox-be-zstd", bw::write_mcap(topics, messages(bw::CloudLayout::Livox, bw::Serialization::CdrBig), {"zstd", 400}));
  out.write("fuzz_mcap", "notime-lz4-no-summary",
            bw::write_mcap(topics, messages(bw::CloudLayout::NoTime, bw::Serialization::CdrLittle), {"lz4", 400, false}));
  out.write("fuzz_mcap", "velodyne-ros1", bw::write_mcap(topics, ros1, {"", 400, true, "ros1"}));
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: " << argv[0] << " OUT_DIR\n";
    return 2;
  }
  SeedWriter out{fs::path(argv[1])};
  try {
    for (const char* sim : {"sim-5515-single", "sim-5515-dual"})
      capture_seeds(out, sim, read_packets(kSource / "fuzz" / "corpus" / (std::string(sim) + ".pcap")), false);
    if (fs::exists(kRealPcap)) {
      capture_seeds(out, "real-16p", read_packets(kRealPcap), true);
    } else {
      std::cout << "liod-fuzz-seeds: " << kRealPcap.string() << " not found: no seeds from real packets\n";
    }
    for (const char* csv : {"helios32_angles.csv", "helios16p_angles.csv"}) {
      const fs::path path = fs::path(LIOD_SHARED_DIR) / "data" / "robosense" / csv;
      if (fs::exists(path)) out.write("fuzz_angles_csv", csv, read_text(path));
    }
    pipeline_seeds(out);
    time_sync_seeds(out);
    mtdata2_seeds(out);
    can_seeds(out);
    pose_seeds(out);
    text_seeds(out);
    bag_seeds(out);
  } catch (const std::exception& e) {
    std::cerr << "liod-fuzz-seeds: " << e.what() << '\n';
    return 1;
  }
  std::cout << "liod-fuzz-seeds: " << out.count() << " seeds in " << argv[1] << '\n';
  return 0;
}
