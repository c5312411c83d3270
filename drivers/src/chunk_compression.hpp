#pragma once
// Inflating bag and MCAP chunks (internal header): bzip2 (ROS 1 "bz2"), the LZ4 frame format
// (ROS 1's roslz4 writes it, as MCAP's "lz4" does) and Zstandard (MCAP "zstd").

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace liod::drivers::detail {

enum class Codec : std::uint8_t { None, Bz2, Lz4Frame, Zstd };

/// Exactly `size` bytes from `compressed`; InputError naming `name` when the data does not
/// inflate to that size (corrupt, cut short, or longer). The output grows as the data inflates,
/// up to `size`: a size field larger than the data never becomes an allocation.
std::vector<std::uint8_t> inflate(Codec codec, std::span<const std::uint8_t> compressed, std::uint64_t size,
                                  const std::string& name);

}  // namespace liod::drivers::detail
