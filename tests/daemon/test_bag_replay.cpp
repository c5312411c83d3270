// `liod replay --bag`: the simulated drive (sim_drive.hpp, 8 s) decoded by the RS-Helios driver
// into sweeps and written with its IMU log (tests/support/bag_writer.hpp) as a ROS 1 bag and an
// MCAP file (zstd chunks, little-endian CDR) in Velodyne's point layout (float32 time in s, uint16
// ring): each replayed through the pipeline must give the same scan poses, bit for bit, as the same
// sweeps handed to the point-cloud path directly (with the stamps at the nanosecond the files hold
// them to). The drive's first second also goes into the other chunk codecs (ROS 1 bz2 and lz4,
// MCAP uncompressed and lz4 with Ouster's layout in big-endian CDR: uint32 t in ns), which must
// hold the same sweeps and samples; the full drive through each would add only decompression time.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "bag_writer.hpp"
#include "liod/daemon/bag_sources.hpp"
#include "liod/daemon/replay.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/ros_messages.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "reference_replay.hpp"
#include "sim_drive.hpp"

namespace liod {
namespace {

namespace fs = std::filesystem;
using test::CloudLayout;

struct Drive {
  std::vector<Scan> scans;
  std::vector<ImuSample> imu;
};

const Drive& decoded(const fs::path& dir) {
  static const Drive d = [&] {
    Drive out;
    drivers::RsHeliosDecoder decoder(drivers::HeliosOptions{}, [&](Scan& scan, const drivers::SweepInfo&) { out.scans.push_back(scan); });
    drivers::PcapReader pcap(dir / "lidar.pcap");
    drivers::UdpDatagram datagram;
    while (pcap.next(datagram)) decoder.feed(datagram.payload, datagram.capture_time_ns);
    out.imu = drivers::read_imu_csv(dir / "imu.csv");
    return out;
  }();
  return d;
}

double stamp_seconds(const test::Stamp& s) { return drivers::RosStamp{s.sec, s.nsec}.seconds(); }

/// What the bag holds of a decoded sweep, as the point-cloud path's input: the stamp and (Ouster)
/// the point times at the nanosecond, no return index.
drivers::CloudSweep held_sweep(const Scan& scan, CloudLayout layout, std::uint64_t sequence) {
  drivers::CloudSweep s;
  s.start_time = stamp_seconds(test::Stamp::of(scan.start_time));
  s.has_time = s.has_ring = true;
  s.sequence = sequence;
  s.points = scan.points;
  for (LidarPoint& p : s.points) {
    p.return_index = 0;
    if (layout == CloudLayout::Ouster) p.time = static_cast<float>(static_cast<double>(std::llround(static_cast<double>(p.time) * 1e9)) * 1e-9);
  }
  return s;
}

/// The drive's sweeps (the first `sweeps`) and the IMU samples up to the last one's end, in time order.
std::vector<test::MessageSpec> messages(const Drive& d, CloudLayout layout, test::Serialization s, std::size_t sweeps) {
  std::vector<test::MessageSpec> out;
  const std::size_t n = std::min(sweeps, d.scans.size());
  const double until = n < d.scans.size() ? d.scans[n - 1].end_time : 1e300;
  std::size_t k = 0;
  test::CloudOptions o;
  o.layout = layout;
  o.serialization = s;
  for (const ImuSample& imu : d.imu) {
    if (imu.time > until) break;
    while (k < n && d.scans[k].end_time <= imu.time) {
      const Scan& scan = d.scans[k++];
      out.push_back({0, test::Stamp::of(scan.end_time).ns(), test::serialize_cloud(scan, test::Stamp::of(scan.start_time), o)});
    }
    out.push_back({1, test::Stamp::of(imu.time).ns(), test::serialize_imu(imu, s)});
  }
  for (; k < n; ++k) {
    out.push_back({0, test::Stamp::of(d.scans[k].end_time).ns(), test::serialize_cloud(d.scans[k], test::Stamp::of(d.scans[k].start_time), o)});
  }
  return out;
}

const std::vector<test::TopicSpec> kTopics{{"/lidar/points", "sensor_msgs/PointCloud2"}, {"/imu/data", "sensor_msgs/Imu"}};

/// A file of the drive's first `sweeps` sweeps, written once per test program: NAME is
/// drive-CODEC.bag (Velodyne layout) or drive-CODEC[-be].mcap (Ouster's in big-endian CDR with
/// -be, else Velodyne's in little-endian CDR); CODEC none, bz2, lz4 or zstd.
const fs::path& bag_file(const fs::path& drive, const std::string& name, std::size_t sweeps = 1000) {
  static const test::ScratchDir dir("bags");
  static std::map<std::string, fs::path> files;
  const std::string key = name + "/" + std::to_string(sweeps);
  if (const auto it = files.find(key); it != files.end()) return it->second;
  const Drive& d = decoded(drive);
  test::Bytes bytes;
  const std::string codec = name.substr(6, name.find_first_of(".-", 6) - 6);
  if (name.ends_with(".bag")) {
    bytes = test::write_ros1_bag(kTopics, messages(d, CloudLayout::Velodyne, test::Serialization::Ros1, sweeps), {codec});
  } else {
    const bool be = name.ends_with("-be.mcap");
    bytes = test::write_mcap(kTopics,
                             be ? messages(d, CloudLayout::Ouster, test::Serialization::CdrBig, sweeps)
                                : messages(d, CloudLayout::Velodyne, test::Serialization::CdrLittle, sweeps),
                             {codec == "none" ? "" : codec});
  }
  const fs::path path = dir.path() / (std::to_string(sweeps) + "-" + name);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return files[key] = path;
}

class VectorLidarSource : public LidarSource {
 public:
  explicit VectorLidarSource(std::vector<drivers::CloudSweep> sweeps) : sweeps_(std::move(sweeps)) {}
  void run(LidarOutput& out, const std::atomic<bool>&) override {
    for (const auto& s : sweeps_) {
      Scan scan = drivers::make_scan(s, drivers::CloudScanConfig{});
      out.sweep(scan);
    }
  }
  std::string describe() const override { return "sweeps"; }

 private:
  std::vector<drivers::CloudSweep> sweeps_;
};

class VectorImuSource : public ImuSource {
 public:
  explicit VectorImuSource(std::vector<ImuSample> samples) : samples_(std::move(samples)) {}
  void run(ImuOutput& out, const std::atomic<bool>&) override {
    for (const auto& s : samples_) out.sample(s);
  }
  std::string describe() const override { return "samples"; }

 private:
  std::vector<ImuSample> samples_;
};

struct Pose {
  double t;
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

std::vector<Pose> run(const Config& config, std::unique_ptr<LidarSource> lidar, std::unique_ptr<ImuSource> imu) {
  PipelineOptions po;
  po.ordering = Ordering::Lockstep;
  po.realtime_threads = false;
  po.imu_rate_poses = false;
  Pipeline pipeline(config, po);
  std::vector<Pose> poses;
  pipeline.add_sink([&](const PoseEvent& ev) {
    if (ev.message.type != pose::MessageType::ImuPose) poses.push_back({ev.message.time, ev.message.position, ev.message.orientation});
  });
  pipeline.start(std::move(lidar), std::move(imu));
  while (!pipeline.finished() && pipeline.error().empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  pipeline.join();
  EXPECT_EQ(pipeline.error(), "");
  return poses;
}

/// The reference: the sweeps as the files hold them, straight into the point-cloud path.
const std::vector<Pose>& reference(const fs::path& drive, CloudLayout layout) {
  static std::map<CloudLayout, std::vector<Pose>> cache;
  auto& poses = cache[layout];
  if (poses.empty()) {
    const Drive& d = decoded(drive);
    std::vector<drivers::CloudSweep> sweeps;
    for (std::size_t i = 0; i < d.scans.size(); ++i) sweeps.push_back(held_sweep(d.scans[i], layout, i));
    std::vector<ImuSample> imu = d.imu;
    for (ImuSample& s : imu) s.time = stamp_seconds(test::Stamp::of(s.time));
    poses = run(test::drive_config(drive), std::make_unique<VectorLidarSource>(sweeps), std::make_unique<VectorImuSource>(imu));
  }
  return poses;
}

void expect_same(const std::vector<Pose>& got, const std::vector<Pose>& want) {
  ASSERT_EQ(got.size(), want.size());
  ASSERT_GT(want.size(), 60U);
  for (std::size_t i = 0; i < want.size(); ++i) {
    ASSERT_EQ(got[i].t, want[i].t) << i;
    ASSERT_EQ(got[i].p, want[i].p) << i;
    ASSERT_EQ(got[i].q.coeffs(), want[i].q.coeffs()) << i;
  }
}

TEST(BagReplay, ARos1BagAndAnMcapGiveThePosesOfThePointCloudPath) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  for (const char* name : {"drive-none.bag", "drive-zstd.mcap"}) {
    SCOPED_TRACE(name);
    const fs::path& path = bag_file(*drive, name);
    auto pace = std::make_shared<PaceClock>();
    const auto poses = run(test::drive_config(*drive), std::make_unique<BagLidarSource>(path.string(), "/lidar/points", pace),
                           std::make_unique<BagImuSource>(path.string(), "/imu/data", pace));
    expect_same(poses, reference(*drive, CloudLayout::Velodyne));
  }
}

// The same drive from its pcap, through the RS-Helios path. The bag holds the decoded drive's
// sweeps at PointCloud2's float32 precision, and the pcap's pipeline makes two more sweeps of the
// packets at the start, so its rolling start searches the speed on other scans: the trajectories
// differ by what a start-up leaves (7.7 cm and 0.13 deg at most over the 8 s, measured), not by a
// reader's error (a wrong time unit or frame moves them by metres).
TEST(BagReplay, ABagReplaysToThePcapsTrajectory) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  auto pace = std::make_shared<PaceClock>();
  const std::vector<std::uint16_t> ports{6699, 7788};
  const auto from_pcap = run(test::drive_config(*drive), std::make_unique<PcapLidarSource>((*drive / "lidar.pcap").string(), ports, pace),
                             std::make_unique<CsvImuSource>((*drive / "imu.csv").string(), pace));
  const auto& from_bag = reference(*drive, CloudLayout::Velodyne);
  // Poses of the same scans, by time (the pcap's pipeline may make a sweep more of the packets
  // at either end than the decoded drive the bag holds), each relative to the first pair: each
  // run's world is its first pose's frame.
  double largest_m = 0.0;
  double largest_deg = 0.0;
  std::size_t paired = 0;
  Eigen::Isometry3d bag_origin = Eigen::Isometry3d::Identity(), pcap_origin = Eigen::Isometry3d::Identity();
  auto isometry = [](const Pose& p) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = p.q.toRotationMatrix();
    t.translation() = p.p;
    return t;
  };
  for (const Pose& b : from_bag) {
    const auto same = std::find_if(from_pcap.begin(), from_pcap.end(), [&](const Pose& p) { return std::abs(p.t - b.t) < 1e-6; });
    if (same == from_pcap.end()) continue;
    if (paired++ == 0) {
      bag_origin = isometry(b).inverse();
      pcap_origin = isometry(*same).inverse();
    }
    const Eigen::Isometry3d difference = (pcap_origin * isometry(*same)).inverse() * (bag_origin * isometry(b));
    largest_m = std::max(largest_m, difference.translation().norm());
    largest_deg = std::max(largest_deg, Eigen::AngleAxisd(difference.linear()).angle() * 180.0 / 3.14159265358979323846);
  }
  ASSERT_GT(paired + 3, from_bag.size());
  std::cout << "[ bag ] " << paired << " of " << from_bag.size() << " poses paired: largest difference from the pcap replay " << largest_m
            << " m, " << largest_deg << " deg" << std::endl;
  EXPECT_LT(largest_m, 0.15);
  EXPECT_LT(largest_deg, 0.3);
}

TEST(BagReplay, EveryChunkCodecHoldsTheDrivesSweepsAndSamples) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  constexpr std::size_t kSweeps = 10;
  const Drive& d = decoded(*drive);
  for (const char* name : {"drive-bz2.bag", "drive-lz4.bag", "drive-none-be.mcap", "drive-lz4-be.mcap"}) {
    SCOPED_TRACE(name);
    const fs::path& path = bag_file(*drive, name, kSweeps);
    const CloudLayout layout = std::string(name).ends_with("-be.mcap") ? CloudLayout::Ouster : CloudLayout::Velodyne;
    auto bag = drivers::open_bag(path);
    std::size_t n = 0;
    bag->read("/lidar/points", [&](const drivers::BagMessage& m) {
      const auto got = drivers::cloud_sweep(drivers::decode_point_cloud2(m.data, m.topic->encoding, name), name, n);
      const auto want = held_sweep(d.scans[n++], layout, 0);
      EXPECT_EQ(got.start_time, want.start_time);
      EXPECT_EQ(got.points.size(), want.points.size());
      for (std::size_t i = 0; i < std::min(got.points.size(), want.points.size()); ++i) {
        const auto &a = got.points[i], &b = want.points[i];
        if (a.x != b.x || a.y != b.y || a.z != b.z || a.time != b.time || a.ring != b.ring || a.intensity != b.intensity) {
          ADD_FAILURE() << "sweep " << n << " point " << i << " differs";
          break;
        }
      }
      return true;
    });
    EXPECT_EQ(n, kSweeps);
    std::size_t k = 0;
    bag->read("/imu/data", [&](const drivers::BagMessage& m) {
      const ImuSample s = drivers::decode_imu(m.data, m.topic->encoding, name);
      EXPECT_EQ(s.time, stamp_seconds(test::Stamp::of(d.imu[k].time)));
      EXPECT_EQ(s.gyro, d.imu[k].gyro);
      EXPECT_EQ(s.accel, d.imu[k].accel);
      ++k;
      return true;
    });
    EXPECT_GT(k, 10 * kSweeps);
  }
}

TEST(BagReplay, TheReplayCommandReadsABagAndNamesTheTopicsWhenOneIsMissing) {
  LIOD_REQUIRE_SIM_DRIVE(drive);
  constexpr std::size_t kSweeps = 30;
  const fs::path bag = bag_file(*drive, "drive-zstd.mcap", kSweeps);
  const test::ScratchDir dir("bag-replay");
  ReplayOptions o;
  o.bag = bag.string();
  o.lidar_topic = "/lidar/points";
  o.imu_topic = "/imu/data";
  o.trajectory_tum = (dir.path() / "scan.tum").string();
  std::ostringstream out;
  ASSERT_EQ(run_replay(test::drive_config(*drive), o, out), 0) << out.str();
  EXPECT_NE(out.str().find("sweeps: 30 read from /lidar/points, 0 points"),
            std::string::npos)
      << out.str();
  EXPECT_GT(test::read_tum(o.trajectory_tum).size(), kSweeps - 5);

  const auto error = [&](const std::string& lidar, const std::string& imu) {
    ReplayOptions bad = o;
    bad.lidar_topic = lidar;
    bad.imu_topic = imu;
    try {
      run_replay(test::drive_config(*drive), bad, out);
    } catch (const drivers::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string listing = "topics:\n  /lidar/points (sensor_msgs/msg/PointCloud2, cdr)\n  /imu/data (sensor_msgs/msg/Imu, cdr)\n";
  const std::string missing = error("/points", "/imu/data");
  EXPECT_NE(missing.find("no topic /points; the MCAP's " + listing), std::string::npos) << missing;
  const std::string swapped = error("/imu/data", "/lidar/points");
  EXPECT_NE(swapped.find("/imu/data is sensor_msgs/msg/Imu, not sensor_msgs/PointCloud2"), std::string::npos) << swapped;
}

}  // namespace
}  // namespace liod
