// ROS 1 bags and MCAP files (bag_reader.hpp) and the PointCloud2 / Imu decoders (ros_messages.hpp)
// on files the test writer makes (tests/support/bag_writer.hpp): every container and chunk codec,
// every drivers' point layout in ROS 1 serialization and CDR of both byte orders, topic listing
// with and without an index, and files cut short or corrupted, which must give an InputError.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "bag_writer.hpp"
#include "liod/drivers/bag_reader.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/ros_messages.hpp"

namespace liod::drivers {
namespace {

namespace bw = liod::test;  // the bag writer (liod::drivers::test is the packet builders')

using bw::Bytes;
using bw::CloudLayout;
using bw::Serialization;

constexpr double kStart = 1'700'000'000.25;  // a stamp of today's magnitude: double's resolution 0.24 µs

/// A small sweep: 4 rings x 300 columns, times 0..0.1 s in firing order.
Scan small_scan(double start) {
  Scan s;
  s.start_time = start;
  for (int k = 0; k < 300; ++k) {
    for (int r = 0; r < 4; ++r) {
      const double a = 2.0 * std::numbers::pi * k / 300.0;
      LidarPoint p;
      p.x = static_cast<float>(10.0 * std::cos(a));
      p.y = static_cast<float>(10.0 * std::sin(a));
      p.z = static_cast<float>(-1.0 + 0.5 * r);
      p.intensity = static_cast<float>(k % 200);
      p.ring = static_cast<std::uint16_t>(r);
      p.time = static_cast<float>(0.1 * k / 300.0 + 2.0e-6 * r);
      s.points.push_back(p);
    }
  }
  return s;
}

ImuSample imu_at(double t) {
  ImuSample s;
  s.time = t;
  s.gyro = Eigen::Vector3d(0.01, -0.02, 0.3 * std::sin(t));
  s.accel = Eigen::Vector3d(0.5, 0.1, 9.81);
  return s;
}

const std::vector<bw::TopicSpec> kTopics{{"/points", "sensor_msgs/PointCloud2"}, {"/imu", "sensor_msgs/Imu"}};

/// Three sweeps and 40 IMU samples in time order; CDR or ROS 1 serialization.
std::vector<bw::MessageSpec> drive_messages(Serialization s, CloudLayout layout = CloudLayout::Velodyne) {
  std::vector<bw::MessageSpec> out;
  for (int i = 0; i < 40; ++i) {
    const double t = kStart + 0.01 * i;
    if (i % 10 == 0) {
      const double start = kStart + 0.1 * (i / 10);
      bw::CloudOptions o;
      o.layout = layout;
      o.serialization = s;
      out.push_back({0, bw::Stamp::of(start + 0.1).ns(), bw::serialize_cloud(small_scan(start), bw::Stamp::of(start), o)});
    }
    out.push_back({1, bw::Stamp::of(t).ns(), bw::serialize_imu(imu_at(t), s)});
  }
  return out;
}

struct Read {
  std::vector<CloudSweep> sweeps;
  std::vector<ImuSample> imu;
};

Read read_all(const Bytes& file, const std::string& name = "drive") {
  auto bag = open_bag(memory_bytes(file, name));
  Read r;
  bag->read("/points", [&](const BagMessage& m) {
    r.sweeps.push_back(cloud_sweep(decode_point_cloud2(m.data, m.topic->encoding, name), name, r.sweeps.size()));
    return true;
  });
  bag->read("/imu", [&](const BagMessage& m) {
    r.imu.push_back(decode_imu(m.data, m.topic->encoding, name));
    return true;
  });
  return r;
}

/// The sweeps and samples read back are the ones written (times to `time_tol` s).
void expect_drive(const Read& r, double time_tol) {
  ASSERT_EQ(r.sweeps.size(), 4U);
  ASSERT_EQ(r.imu.size(), 40U);
  for (std::size_t i = 0; i < r.sweeps.size(); ++i) {
    const Scan want = small_scan(kStart + 0.1 * static_cast<double>(i));
    const CloudSweep& got = r.sweeps[i];
    ASSERT_EQ(got.points.size(), want.points.size());
    EXPECT_TRUE(got.has_ring);
    EXPECT_NEAR(got.start_time, want.start_time, 1e-6);
    for (std::size_t k = 0; k < want.points.size(); ++k) {
      const auto &a = got.points[k], &b = want.points[k];
      ASSERT_EQ(a.x, b.x);
      ASSERT_EQ(a.y, b.y);
      ASSERT_EQ(a.z, b.z);
      ASSERT_EQ(a.ring, b.ring);
      ASSERT_NEAR(a.time, b.time, time_tol) << "point " << k;
    }
  }
  for (std::size_t i = 0; i < r.imu.size(); ++i) {
    const ImuSample want = imu_at(kStart + 0.01 * static_cast<double>(i));
    EXPECT_NEAR(r.imu[i].time, want.time, 1e-6);
    EXPECT_EQ(r.imu[i].gyro, want.gyro);
    EXPECT_EQ(r.imu[i].accel, want.accel);
  }
}

TEST(BagReader, Ros1BagsOfEveryChunkCodecReadBackAsWritten) {
  for (const char* codec : {"none", "bz2", "lz4"}) {
    SCOPED_TRACE(codec);
    bw::Ros1BagOptions o;
    o.compression = codec;
    o.chunk_bytes = 20'000;  // several chunks
    const Bytes file = bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1), o);
    auto bag = open_bag(memory_bytes(file, "drive.bag"));
    EXPECT_STREQ(bag->format(), "ROS 1 bag");
    const auto topics = bag->topics();
    ASSERT_EQ(topics.size(), 2U);
    EXPECT_EQ(topics[0].name, "/points");
    EXPECT_EQ(topics[0].type, "sensor_msgs/PointCloud2");
    EXPECT_EQ(topics[1].type, "sensor_msgs/Imu");
    expect_drive(read_all(file), 0.0);
  }
}

TEST(BagReader, McapFilesOfEveryChunkCodecReadBackAsWritten) {
  for (const char* codec : {"", "lz4", "zstd"}) {
    SCOPED_TRACE(codec);
    bw::McapOptions o;
    o.compression = codec;
    o.chunk_bytes = 20'000;
    const Bytes file = bw::write_mcap(kTopics, drive_messages(Serialization::CdrLittle), o);
    auto bag = open_bag(memory_bytes(file, "drive.mcap"));
    EXPECT_STREQ(bag->format(), "MCAP");
    const auto topics = bag->topics();
    ASSERT_EQ(topics.size(), 2U);
    EXPECT_EQ(topics[0].type, "sensor_msgs/msg/PointCloud2");
    EXPECT_EQ(topics[1].type, "sensor_msgs/msg/Imu");
    EXPECT_EQ(topics[1].encoding, MessageEncoding::Cdr);
    expect_drive(read_all(file), 0.0);
  }
}

TEST(BagReader, BigEndianCdrAndRos1MessagesInMcap) {
  expect_drive(read_all(bw::write_mcap(kTopics, drive_messages(Serialization::CdrBig))), 0.0);
  bw::McapOptions o;
  o.message_encoding = "ros1";
  expect_drive(read_all(bw::write_mcap(kTopics, drive_messages(Serialization::Ros1), o)), 0.0);
}

TEST(BagReader, EveryDriversTimeConventionGivesThePointTimes) {
  // ns fields round to the nanosecond; Hesai's absolute float64 seconds carry the stamp's 0.24 µs.
  const std::pair<CloudLayout, double> layouts[] = {
      {CloudLayout::Velodyne, 0.0}, {CloudLayout::Ouster, 1e-9}, {CloudLayout::Livox, 1e-9}, {CloudLayout::Hesai, 3e-7}};
  for (const auto& [layout, tol] : layouts) {
    for (const Serialization s : {Serialization::Ros1, Serialization::CdrLittle, Serialization::CdrBig}) {
      SCOPED_TRACE(static_cast<int>(layout) * 10 + static_cast<int>(s));
      expect_drive(read_all(bw::write_mcap(kTopics, drive_messages(s, layout), {"zstd", 768 * 1024, true,
                                                                                  s == Serialization::Ros1 ? "ros1" : "cdr"})),
                   tol);
    }
  }
}

TEST(BagReader, OrganizedBigEndianCloudsWithRowPaddingAndNanPoints) {
  Scan scan = small_scan(kStart);
  scan.points[5].x = std::numeric_limits<float>::quiet_NaN();  // is_dense false: a return that did not come back
  bw::CloudOptions o;
  o.layout = CloudLayout::Ouster;
  o.serialization = Serialization::CdrBig;
  o.big_endian_points = true;
  o.height = 4;
  o.row_padding = 13;
  const Bytes msg = bw::serialize_cloud(scan, bw::Stamp::of(kStart), o);
  const PointCloud2 cloud = decode_point_cloud2(msg, MessageEncoding::Cdr, "m");
  EXPECT_EQ(cloud.height, 4U);
  EXPECT_TRUE(cloud.is_bigendian);
  CloudConversionStats stats;
  const CloudSweep sweep = cloud_sweep(cloud, "m", 7, &stats);
  EXPECT_EQ(stats.not_finite, 1U);
  ASSERT_EQ(sweep.points.size(), scan.points.size() - 1);
  EXPECT_EQ(sweep.sequence, 7U);
  EXPECT_EQ(sweep.points[5].y, scan.points[6].y);
  EXPECT_EQ(sweep.points.back().ring, scan.points.back().ring);
}

TEST(BagReader, CloudsWithoutTimeStartAtTheirStampAndTimeFromAzimuth) {
  bw::CloudOptions o;
  o.layout = CloudLayout::NoTime;
  const Bytes msg = bw::serialize_cloud(small_scan(kStart), bw::Stamp::of(kStart), o);
  const CloudSweep sweep = cloud_sweep(decode_point_cloud2(msg, MessageEncoding::Ros1, "m"), "m", 0);
  EXPECT_FALSE(sweep.has_time);
  EXPECT_TRUE(sweep.has_ring);
  const bw::Stamp stamp = bw::Stamp::of(kStart);
  EXPECT_EQ(sweep.start_time, (RosStamp{stamp.sec, stamp.nsec}.seconds()));
  const Scan scan = make_scan(sweep, CloudScanConfig{});
  EXPECT_EQ(scan.points.size(), sweep.points.size());
  EXPECT_NEAR(scan.end_time - scan.start_time, 0.1, 3e-7);  // the sweep period, at a stamp's resolution
}

TEST(BagReader, TopicsComeFromTheIndexOrFromReadingThrough) {
  bw::Ros1BagOptions unindexed;
  unindexed.indexed = false;
  bw::McapOptions no_summary;
  no_summary.summary = false;
  for (const Bytes& file : {bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1), unindexed),
                            bw::write_mcap(kTopics, drive_messages(Serialization::CdrLittle), no_summary)}) {
    auto bag = open_bag(memory_bytes(file, "f"));
    const auto topics = bag->topics();
    ASSERT_EQ(topics.size(), 2U) << bag->format();
    EXPECT_EQ(topics[0].name, "/points");
    EXPECT_EQ(topics[1].name, "/imu");
    expect_drive(read_all(file), 0.0);
  }
}

TEST(BagReader, ReadsOnlyTheTopicAskedForAndStopsWhenTold) {
  const Bytes file = bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1));
  auto bag = open_bag(memory_bytes(file, "f"));
  std::size_t n = 0;
  bag->read("/imu", [&](const BagMessage& m) {
    EXPECT_EQ(m.topic->name, "/imu");
    return ++n < 5;
  });
  EXPECT_EQ(n, 5U);
  bag->read("/nothing", [](const BagMessage&) -> bool { throw std::logic_error("no message expected"); });
  EXPECT_EQ(describe_topics(bag->topics()), "  /points (sensor_msgs/PointCloud2, ros1)\n  /imu (sensor_msgs/Imu, ros1)\n");
}

/// Opening and reading every topic either works or throws InputError naming the input.
bool reads_or_input_error(const Bytes& file, const std::string& name, std::string* error = nullptr) {
  try {
    auto bag = open_bag(memory_bytes(file, name));
    (void)bag->topics();
    read_all(file, name);
    return true;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    if (error != nullptr) *error = e.what();
    return false;
  }
}

TEST(BagReader, FilesCutShortGiveAnInputError) {
  bw::Ros1BagOptions ro;
  ro.compression = "lz4";
  ro.chunk_bytes = 20'000;
  bw::McapOptions mo;
  mo.compression = "zstd";
  mo.chunk_bytes = 20'000;
  for (const Bytes& file : {bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1), ro),
                            bw::write_mcap(kTopics, drive_messages(Serialization::CdrLittle), mo)}) {
    std::size_t errors = 0, cuts = 0;
    for (std::size_t cut = 0; cut + 2000 < file.size(); cut += 997) {  // up to the index or summary
      const Bytes part(file.begin(), file.begin() + static_cast<std::ptrdiff_t>(cut));
      ++cuts;
      if (!reads_or_input_error(part, "cut.bag")) ++errors;
    }
    EXPECT_EQ(errors, cuts) << "every cut before the end loses a record";
  }
  std::string error;
  const Bytes mcap = bw::write_mcap(kTopics, drive_messages(Serialization::CdrLittle), mo);
  EXPECT_FALSE(reads_or_input_error(Bytes(mcap.begin(), mcap.begin() + 30'000), "cut.mcap", &error));
  EXPECT_NE(error.find("past the end of the file"), std::string::npos) << error;
}

TEST(BagReader, CorruptedChunksGiveAnInputError) {
  const auto corrupt = [](Bytes file, std::size_t at) {
    for (std::size_t i = at; i < at + 8; ++i) file[i] ^= 0x5A;
    return file;
  };
  bw::McapOptions plain;  // an uncompressed chunk: the CRC finds it
  const Bytes mcap = bw::write_mcap(kTopics, drive_messages(Serialization::CdrLittle), plain);
  std::string error;
  EXPECT_FALSE(reads_or_input_error(corrupt(mcap, 5000), "bad.mcap", &error));
  EXPECT_NE(error.find("CRC"), std::string::npos) << error;
  for (const char* codec : {"bz2", "lz4"}) {
    bw::Ros1BagOptions o;
    o.compression = codec;
    const Bytes bag = bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1), o);
    EXPECT_FALSE(reads_or_input_error(corrupt(bag, 4096 + 13 + 2000), "bad.bag", &error)) << codec;
    EXPECT_NE(error.find(std::string(codec) + " chunk"), std::string::npos) << error;
  }
  // Corrupted anywhere, the reader gives an InputError or data, never a crash.
  bw::Ros1BagOptions o;
  o.compression = "none";
  const Bytes bag = bw::write_ros1_bag(kTopics, drive_messages(Serialization::Ros1), o);
  for (std::size_t at = 0; at + 8 < bag.size(); at += 1499) reads_or_input_error(corrupt(bag, at), "bad.bag");
}

TEST(BagReader, OtherFilesAreRefusedByName) {
  std::string error;
  const std::string v12 = "#ROSBAG V1.2\n";
  EXPECT_FALSE(reads_or_input_error(Bytes(v12.begin(), v12.end()), "old.bag", &error));
  EXPECT_NE(error.find("only format 2.0"), std::string::npos) << error;
  const std::string csv = "time_s,gyro_x\n";
  EXPECT_FALSE(reads_or_input_error(Bytes(csv.begin(), csv.end()), "imu.csv", &error));
  EXPECT_NE(error.find("neither a ROS 1 bag"), std::string::npos) << error;
}

TEST(BagReader, MessagesThatAreNotWholeGiveAnInputError) {
  bw::CloudOptions o;
  o.layout = CloudLayout::Velodyne;
  o.serialization = Serialization::CdrLittle;
  Bytes msg = bw::serialize_cloud(small_scan(kStart), bw::Stamp::of(kStart), o);
  Bytes encapsulation = msg;
  encapsulation[1] = 0x03;  // PL_CDR_LE: parameter lists, which ROS 2 does not send
  EXPECT_THROW(decode_point_cloud2(encapsulation, MessageEncoding::Cdr, "m"), InputError);
  for (const std::size_t cut : {std::size_t{3}, std::size_t{30}, msg.size() - 200}) {
    EXPECT_THROW(decode_point_cloud2(std::span(msg).first(cut), MessageEncoding::Cdr, "m"), InputError) << cut;
  }
  EXPECT_THROW(decode_imu(msg, MessageEncoding::Cdr, "m"), InputError);  // a cloud is no IMU sample

  o.layout = CloudLayout::NoTime;
  o.serialization = Serialization::Ros1;
  Scan scan = small_scan(kStart);
  const Bytes no_time = bw::serialize_cloud(scan, bw::Stamp::of(kStart), o);
  PointCloud2 cloud = decode_point_cloud2(no_time, MessageEncoding::Ros1, "m");
  cloud.fields.pop_back();  // ring
  try {
    cloud_sweep(cloud, "m", 0);
    ADD_FAILURE() << "a cloud without ring was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no ring or line field (fields: x y z intensity)"), std::string::npos) << e.what();
  }
  cloud = decode_point_cloud2(no_time, MessageEncoding::Ros1, "m");
  cloud.row_step += 1;  // rows no longer fit the data
  EXPECT_THROW(cloud_sweep(cloud, "m", 0), InputError);
  cloud = decode_point_cloud2(no_time, MessageEncoding::Ros1, "m");
  cloud.fields[3].offset = cloud.point_step - 2;  // intensity past the point's end
  EXPECT_THROW(cloud_sweep(cloud, "m", 0), InputError);
}

}  // namespace
}  // namespace liod::drivers
