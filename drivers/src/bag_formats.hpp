#pragma once
// The two container readers behind open_bag (internal header): ros_bag.cpp and mcap.cpp.

#include <memory>

#include "liod/drivers/bag_reader.hpp"

namespace liod::drivers::detail {

/// The bytes begin with "#ROSBAG V2.0\n".
std::unique_ptr<BagReader> make_ros1_bag_reader(std::unique_ptr<ByteSource> bytes, BagLimits limits);
/// The bytes begin with MCAP's magic.
std::unique_ptr<BagReader> make_mcap_reader(std::unique_ptr<ByteSource> bytes, BagLimits limits);

/// The topics without repeats (a topic recorded from several publishers has a connection or
/// channel each), in their first one's order.
std::vector<BagTopic> distinct_topics(const std::vector<BagTopic>& all);

/// `n` bytes at `offset` of `source`, after checking they lie in it: InputError naming `what`
/// and the offset otherwise (a length field past the end of the file: cut short or corrupt).
std::vector<std::uint8_t> read_range(const ByteSource& source, std::uint64_t offset, std::uint64_t n, const std::string& what);

}  // namespace liod::drivers::detail
