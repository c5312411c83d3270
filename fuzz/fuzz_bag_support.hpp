#pragma once
// The body of the bag fuzz targets (fuzz_ros_bag, fuzz_mcap): the input as a file, opened by its
// magic, every topic listed and read, each PointCloud2 or Imu message decoded and each cloud made
// into a scan. Reading must end in data or an InputError naming the file, never a crash, a read
// outside the input or an allocation beyond what the input inflates to (BagLimits caps a chunk at
// 16 MiB here). A scan made from a cloud has every ring below its beam count and its points in
// time order; an IMU sample is finite.

#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "fuzz_support.hpp"
#include "liod/drivers/bag_reader.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/ros_messages.hpp"

namespace liod::fuzz {

inline void read_message(const drivers::BagMessage& m, const std::string& name) {
  if (drivers::is_imu_type(m.topic->type)) {
    const ImuSample s = drivers::decode_imu(m.data, m.topic->encoding, name);
    require(s.gyro.allFinite() && s.accel.allFinite(), "an IMU sample that is not finite");
    return;
  }
  if (!drivers::is_point_cloud2_type(m.topic->type)) return;
  const drivers::CloudSweep sweep = drivers::cloud_sweep(drivers::decode_point_cloud2(m.data, m.topic->encoding, name), name, 0);
  const Scan scan = drivers::make_scan(sweep, drivers::CloudScanConfig{});
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    require(scan.points[i].ring < scan.beam_count, "ring beyond the beam count");
    require(std::isfinite(scan.points[i].time) && scan.points[i].time >= 0.0F, "a point time that is not a time after the start");
    if (i > 0) require(scan.points[i - 1].time <= scan.points[i].time, "points not in time order");
  }
}

/// `magic` is put before inputs that do not begin with it, so that mutations stay in the format.
inline int fuzz_bag(const std::uint8_t* data, std::size_t size, std::span<const std::uint8_t> magic) {
  std::vector<std::uint8_t> bytes(data, data + size);
  if (size < magic.size() || !std::equal(magic.begin(), magic.end(), data)) bytes.insert(bytes.begin(), magic.begin(), magic.end());
  const std::string name = "fuzz.bag";
  drivers::BagLimits limits;
  limits.max_chunk_bytes = 16U << 20;
  try {
    auto bag = drivers::open_bag(drivers::memory_bytes(bytes, name), limits);
    for (const drivers::BagTopic& topic : bag->topics()) {
      bag->read(topic.name, [&](const drivers::BagMessage& m) {
        touch(m.data);
        read_message(m, name);
        return true;
      });
    }
  } catch (const drivers::InputError& e) {
    require(std::string(e.what()).find(name) != std::string::npos, "error message does not name the file");
  }
  return 0;
}

}  // namespace liod::fuzz
