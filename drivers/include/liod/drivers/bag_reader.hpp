#pragma once
// Recorded ROS topics without ROS: ROS 1 bags (format 2.0, chunks uncompressed, bz2 or lz4) and
// MCAP files (ROS 2's default recording format; chunks uncompressed, zstd or lz4), told apart by
// their magic bytes. Both are read by hand against their published specifications (ROS wiki
// "Bags/Format/2.0", mcap.dev/spec) with libbz2, liblz4 and libzstd for the chunks: MCAP has no
// Debian package, and Debian's ROS 1 reader (librosbag-storage-dev) brings 37 packages along
// (Boost, pluginlib, ament, gpgme) for what is here a few hundred lines, and could not be fuzzed
// with the rest (docs/design.md, "Other LiDARs").
//
// A reader streams the file: records are read one at a time, a chunk is inflated into a buffer
// that grows only as far as its data really inflates (never to a size a length field claims), and
// a message's bytes are handed to the caller while the chunk is in memory. Malformed input (a
// record past the end of the file, a chunk that does not inflate to its stated size, a bad CRC)
// throws InputError naming the file and the byte offset.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace liod::drivers {

/// How a topic's messages are serialized: ROS 1's (little-endian, packed), ROS 2's CDR, or
/// another that liod does not decode (MCAP also carries protobuf, JSON, ...).
enum class MessageEncoding : std::uint8_t { Ros1, Cdr, Other };

struct BagTopic {
  std::string name;
  /// As the file gives it: "sensor_msgs/PointCloud2" in a ROS 1 bag, "sensor_msgs/msg/PointCloud2"
  /// in a ROS 2 MCAP (the schema's name; "" without a schema).
  std::string type;
  MessageEncoding encoding = MessageEncoding::Ros1;
  /// The encoding as the file names it (MCAP's message_encoding: "cdr", "ros1"; a ROS 1 bag: "ros1").
  std::string encoding_name;
};

struct BagMessage {
  const BagTopic* topic = nullptr;
  std::int64_t log_time_ns = 0;  ///< when the recorder received it (not the message's own stamp)
  std::span<const std::uint8_t> data;  ///< the serialized message; valid during the callback only
};

struct BagLimits {
  /// A chunk that inflates to more than this is refused (the fuzz targets set less).
  std::uint64_t max_chunk_bytes = std::uint64_t{1} << 30;
};

/// Random access to the file's bytes: the file itself, or memory (tests, fuzzing).
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  [[nodiscard]] virtual std::uint64_t size() const = 0;
  /// Fills `out` from `offset`; InputError when the range is not wholly in the source.
  virtual void read(std::uint64_t offset, std::span<std::uint8_t> out) const = 0;
  [[nodiscard]] virtual const std::string& name() const = 0;
};

/// InputError naming the file when it cannot be opened.
std::unique_ptr<ByteSource> open_file_bytes(const std::filesystem::path& path);
/// `bytes` must outlive the source.
std::unique_ptr<ByteSource> memory_bytes(std::span<const std::uint8_t> bytes, std::string name);

class BagReader {
 public:
  virtual ~BagReader() = default;
  /// "ROS 1 bag" or "MCAP".
  [[nodiscard]] virtual const char* format() const = 0;
  /// Every topic with its type, from the file's index or summary where it has one, else by
  /// reading the file through.
  virtual std::vector<BagTopic> topics() = 0;
  /// Calls `visit` with each message on `topic` in file order (all of the topic's connections or
  /// channels); stops early when `visit` returns false.
  virtual void read(const std::string& topic, const std::function<bool(const BagMessage&)>& visit) = 0;
};

/// A ROS 1 bag or an MCAP file by its first bytes; InputError when it is neither (or a ROS 1 bag
/// of another version than 2.0).
std::unique_ptr<BagReader> open_bag(std::unique_ptr<ByteSource> bytes, BagLimits limits = {});
std::unique_ptr<BagReader> open_bag(const std::filesystem::path& path);

/// The topics as "NAME (TYPE)" lines, for errors that list what a file holds.
std::string describe_topics(const std::vector<BagTopic>& topics);

}  // namespace liod::drivers
