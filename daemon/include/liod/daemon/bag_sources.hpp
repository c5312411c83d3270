#pragma once
// `liod replay --bag FILE --lidar-topic T --imu-topic T`: a ROS 1 bag's or an MCAP file's
// sensor_msgs/PointCloud2 and sensor_msgs/Imu topics (drivers/bag_reader.hpp, ros_messages.hpp)
// as the pipeline's LiDAR and IMU sources, on the pace clock of the other file sources. Clouds go
// through the point-cloud path (cloud_sweep.hpp) like KITTI's; each reads the file on its own.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "liod/daemon/pipeline.hpp"
#include "liod/daemon/sources.hpp"

namespace liod {

class BagLidarSource : public LidarSource {
 public:
  BagLidarSource(std::string path, std::string topic, std::shared_ptr<const PaceClock> pace);
  void run(LidarOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return topic_ + " in " + path_; }
  std::size_t sweeps_read() const { return read_.load(); }
  /// Points without finite coordinates, or too near (the point-cloud path drops them).
  std::size_t points_dropped() const { return dropped_.load(); }

 private:
  std::string path_, topic_;
  std::shared_ptr<const PaceClock> pace_;
  std::atomic<std::size_t> read_{0}, dropped_{0};
};

class BagImuSource : public ImuSource {
 public:
  BagImuSource(std::string path, std::string topic, std::shared_ptr<const PaceClock> pace);
  void run(ImuOutput& out, const std::atomic<bool>& stop) override;
  std::string describe() const override { return topic_ + " in " + path_; }

 private:
  std::string path_, topic_;
  std::shared_ptr<const PaceClock> pace_;
};

/// Checks that the file holds `lidar_topic` as sensor_msgs/PointCloud2 and `imu_topic` as
/// sensor_msgs/Imu, in an encoding liod decodes; InputError listing the file's topics otherwise.
void check_bag_topics(const std::string& path, const std::string& lidar_topic, const std::string& imu_topic);

/// The header stamp (ns) of the topic's first message, a PointCloud2 or an Imu; 0 when it has none.
std::int64_t first_bag_cloud_ns(const std::string& path, const std::string& topic);
std::int64_t first_bag_imu_ns(const std::string& path, const std::string& topic);

}  // namespace liod
