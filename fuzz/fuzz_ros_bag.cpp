// Fuzz target: ROS 1 bags (bag_reader.hpp) with the PointCloud2 and Imu messages in them
// (ros_messages.hpp); fuzz_bag_support.hpp says what must hold.

#include "fuzz_bag_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr std::uint8_t kMagic[] = {'#', 'R', 'O', 'S', 'B', 'A', 'G', ' ', 'V', '2', '.', '0', '\n'};
  return liod::fuzz::fuzz_bag(data, size, kMagic);
}
