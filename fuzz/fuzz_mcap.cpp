// Fuzz target: MCAP files (bag_reader.hpp) with the PointCloud2 and Imu messages in them
// (ros_messages.hpp); fuzz_bag_support.hpp says what must hold.

#include "fuzz_bag_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr std::uint8_t kMagic[] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
  return liod::fuzz::fuzz_bag(data, size, kMagic);
}
