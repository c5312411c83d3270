#include "liod/daemon/bag_sources.hpp"

#include <algorithm>
#include <cmath>

#include "liod/drivers/bag_reader.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/ros_messages.hpp"

namespace liod {
namespace {

std::string message_name(const std::string& path, const std::string& topic, std::size_t index) {
  return path + ": " + topic + " message " + std::to_string(index + 1);
}

}  // namespace

BagLidarSource::BagLidarSource(std::string path, std::string topic, std::shared_ptr<const PaceClock> pace)
    : path_(std::move(path)), topic_(std::move(topic)), pace_(std::move(pace)) {}

void BagLidarSource::run(LidarOutput& out, const std::atomic<bool>& stop) {
  // Clouds carry their rings; without per-point time, times come from azimuth as for a
  // Velodyne or Ouster head (clockwise from behind, 10 Hz: CloudScanConfig's defaults).
  const drivers::CloudScanConfig config;
  Scan scan;
  std::size_t n = 0;
  drivers::open_bag(path_)->read(topic_, [&](const drivers::BagMessage& m) {
    const std::string name = message_name(path_, topic_, n);
    const drivers::PointCloud2 cloud = drivers::decode_point_cloud2(m.data, m.topic->encoding, name);
    drivers::CloudConversionStats converted;
    const drivers::CloudSweep sweep = drivers::cloud_sweep(cloud, name, n, &converted);
    drivers::CloudScanStats stats;
    scan = drivers::make_scan(sweep, config, &stats);
    // A sweep is whole once its last return is in: released at its end time.
    if (!pace_->wait_until(to_ns(scan.end_time), stop, [&] { out.heartbeat(); })) return false;
    dropped_.fetch_add(converted.not_finite + stats.no_beam + stats.too_near);
    out.sweep(scan);
    read_.store(++n);
    return !stop.load();
  });
}

BagImuSource::BagImuSource(std::string path, std::string topic, std::shared_ptr<const PaceClock> pace)
    : path_(std::move(path)), topic_(std::move(topic)), pace_(std::move(pace)) {}

void BagImuSource::run(ImuOutput& out, const std::atomic<bool>& stop) {
  std::size_t n = 0;
  drivers::open_bag(path_)->read(topic_, [&](const drivers::BagMessage& m) {
    const ImuSample s = drivers::decode_imu(m.data, m.topic->encoding, message_name(path_, topic_, n));
    if (!pace_->wait_until(to_ns(s.time), stop, [&] { out.heartbeat(); })) return false;
    out.sample(s);
    if ((++n & 63) == 0) out.heartbeat();
    return !stop.load();
  });
}

void check_bag_topics(const std::string& path, const std::string& lidar_topic, const std::string& imu_topic) {
  const auto bag = drivers::open_bag(path);
  const auto topics = bag->topics();
  const auto check = [&](const std::string& topic, bool (*is_type)(const std::string&), const char* wanted) {
    const auto it = std::find_if(topics.begin(), topics.end(), [&](const drivers::BagTopic& t) { return t.name == topic; });
    std::string why;
    if (it == topics.end()) why = "no topic " + topic;
    else if (!is_type(it->type)) why = topic + " is " + (it->type.empty() ? "of no type" : it->type) + ", not " + wanted;
    else if (it->encoding == drivers::MessageEncoding::Other) why = topic + " is encoded as " + it->encoding_name + ", not ros1 or cdr";
    if (!why.empty()) throw drivers::InputError(path, 0, why + "; the " + bag->format() + "'s topics:\n" + drivers::describe_topics(topics));
  };
  check(lidar_topic, drivers::is_point_cloud2_type, "sensor_msgs/PointCloud2");
  check(imu_topic, drivers::is_imu_type, "sensor_msgs/Imu");
}

std::int64_t first_bag_cloud_ns(const std::string& path, const std::string& topic) {
  std::int64_t t = 0;
  drivers::open_bag(path)->read(topic, [&](const drivers::BagMessage& m) {
    t = to_ns(drivers::decode_point_cloud2(m.data, m.topic->encoding, message_name(path, topic, 0)).stamp.seconds());
    return false;
  });
  return t;
}

std::int64_t first_bag_imu_ns(const std::string& path, const std::string& topic) {
  std::int64_t t = 0;
  drivers::open_bag(path)->read(topic, [&](const drivers::BagMessage& m) {
    t = to_ns(drivers::decode_imu(m.data, m.topic->encoding, message_name(path, topic, 0)).time);
    return false;
  });
  return t;
}

}  // namespace liod
