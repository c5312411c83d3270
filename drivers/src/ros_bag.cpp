// ROS 1 bag format 2.0 (ROS wiki, "Bags/Format/2.0"): after the version line "#ROSBAG V2.0\n",
// records of <header length u32><header: fields <length u32><name>=<value>><data length u32><data>,
// all little-endian. The header's "op" field says what a record is: the bag header (0x03: where the
// index begins), chunks (0x05: "compression" none|bz2|lz4, "size" inflated) holding connection
// (0x07) and message data (0x02) records, index data (0x04) after each chunk, and at the index
// position every connection again and the chunk infos (0x06). A connection record's data is a
// connection header (fields as above: type, md5sum, message_definition); a message's header has
// "conn" and "time" (u32 seconds, u32 nanoseconds).

#include <algorithm>
#include <map>
#include <optional>
#include <string_view>
#include <utility>

#include "bag_formats.hpp"
#include "chunk_compression.hpp"
#include "field_cursor.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers::detail {
namespace {

constexpr std::uint64_t kVersionLineBytes = 13;
enum BagOp : std::uint8_t { kBagMessageData = 0x02, kBagHeader = 0x03, kBagChunk = 0x05, kBagConnection = 0x07 };

/// A record header's (or a connection header's) name=value fields.
class Fields {
 public:
  Fields(std::span<const std::uint8_t> bytes, const std::string& name, std::uint64_t offset) {
    FieldCursor c(bytes, name, offset);
    while (!c.at_end()) {
      const auto field = c.bytes(c.u32("header field length"), "header field");
      const auto eq = std::find(field.begin(), field.end(), std::uint8_t{'='});
      if (eq == field.end()) c.fail("header field without '='");
      const auto split = static_cast<std::size_t>(eq - field.begin());
      items_.emplace_back(std::string(reinterpret_cast<const char*>(field.data()), split), field.subspan(split + 1));
    }
    name_ = name;
    offset_ = offset;
  }
  [[nodiscard]] std::optional<std::span<const std::uint8_t>> find(std::string_view key) const {
    for (const auto& [k, v] : items_) {
      if (k == key) return v;
    }
    return std::nullopt;
  }
  /// A field of exactly `size` bytes (an integer), else InputError.
  [[nodiscard]] std::span<const std::uint8_t> fixed(std::string_view key, std::size_t size) const {
    const auto v = find(key);
    if (!v || v->size() != size) fail("field '" + std::string(key) + "' missing or not " + std::to_string(size) + " bytes");
    return *v;
  }
  [[nodiscard]] std::uint8_t op() const { return fixed("op", 1)[0]; }
  [[nodiscard]] std::uint32_t u32(std::string_view key) const { return load_le32(fixed(key, 4).data()); }
  [[nodiscard]] std::uint64_t u64(std::string_view key) const { return load_le64(fixed(key, 8).data()); }
  [[nodiscard]] std::string text(std::string_view key) const {
    const auto v = find(key);
    if (!v) fail("field '" + std::string(key) + "' missing");
    return {reinterpret_cast<const char*>(v->data()), v->size()};
  }
  [[noreturn]] void fail(const std::string& why) const {
    throw InputError(name_, 0, "record at byte offset " + std::to_string(offset_) + ": " + why);
  }

 private:
  std::vector<std::pair<std::string, std::span<const std::uint8_t>>> items_;
  std::string name_;
  std::uint64_t offset_ = 0;
};

using BagVisit = std::function<bool(const BagMessage&)>;

class Ros1BagReader : public BagReader {
 public:
  Ros1BagReader(std::unique_ptr<ByteSource> bytes, BagLimits limits) : src_(std::move(bytes)), limits_(limits) {
    const auto head = read_head(kVersionLineBytes);
    const Fields f(head.header, src_->name(), kVersionLineBytes);
    if (f.op() != kBagHeader) f.fail("the first record is not the bag header (op 0x03)");
    index_pos_ = f.u64("index_pos");
    connection_count_ = f.u32("conn_count");
  }

  const char* format() const override { return "ROS 1 bag"; }

  std::vector<BagTopic> topics() override {
    // The index at index_pos repeats every connection; a bag whose recording was cut has none
    // (index_pos 0) and is read through.
    if (index_pos_ >= kVersionLineBytes && index_pos_ < src_->size()) {
      for (std::uint64_t pos = index_pos_; pos < src_->size();) pos = file_record(pos, nullptr, nullptr);
    }
    if (index_pos_ == 0 || connections_.size() < connection_count_) walk(nullptr, nullptr);
    std::vector<BagTopic> all;
    for (const auto& entry : connections_) all.push_back(entry.second);
    return distinct_topics(all);
  }

  void read(const std::string& topic, const BagVisit& visit) override { walk(&topic, &visit); }

 private:
  struct Head {
    std::vector<std::uint8_t> header;
    std::uint64_t data_offset = 0;
    std::uint64_t data_length = 0;
  };

  Head read_head(std::uint64_t pos) const {
    Head h;
    const auto header_length = read_range(*src_, pos, 4, "record header length");
    h.header = read_range(*src_, pos + 4, load_le32(header_length.data()), "record header");
    const std::uint64_t at = pos + 4 + h.header.size();
    h.data_length = load_le32(read_range(*src_, at, 4, "record data length").data());
    h.data_offset = at + 4;
    if (h.data_length > src_->size() - h.data_offset) read_range(*src_, h.data_offset, h.data_length, "record data");  // throws
    return h;
  }

  /// Reads the file's records from the start; false when `visit` stopped.
  bool walk(const std::string* topic, const BagVisit* visit) {
    for (std::uint64_t pos = kVersionLineBytes; pos < src_->size();) {
      pos = file_record(pos, topic, visit);
      if (pos == 0) return false;
    }
    return true;
  }

  /// The record at `pos` of the file; returns the next record's offset, 0 when `visit` stopped.
  std::uint64_t file_record(std::uint64_t pos, const std::string* topic, const BagVisit* visit) {
    const Head h = read_head(pos);
    const Fields f(h.header, src_->name(), pos);
    const std::uint64_t next = h.data_offset + h.data_length;
    const std::uint8_t op = f.op();
    if (op == kBagChunk) {
      const std::string where = src_->name() + ": chunk at byte offset " + std::to_string(pos);
      const std::uint64_t size = f.u32("size");
      if (size > limits_.max_chunk_bytes) f.fail("chunk of " + std::to_string(size) + " bytes, more than the limit");
      const auto stored = read_range(*src_, h.data_offset, h.data_length, "chunk data");
      const std::vector<std::uint8_t> records = inflate(codec(f), stored, size, where);
      return chunk_records(records, where, topic, visit) ? next : 0;
    }
    if (op == kBagConnection || op == kBagMessageData) {
      const auto data = read_range(*src_, h.data_offset, h.data_length, "record data");
      return record(f, data, topic, visit) ? next : 0;
    }
    return next;  // bag header, index data, chunk info, and ops this reader does not know
  }

  static Codec codec(const Fields& f) {
    const std::string c = f.text("compression");
    if (c == "none") return Codec::None;
    if (c == "bz2") return Codec::Bz2;
    if (c == "lz4") return Codec::Lz4Frame;
    f.fail("chunk compression '" + c + "' (expected none, bz2 or lz4)");
  }

  bool chunk_records(std::span<const std::uint8_t> records, const std::string& where, const std::string* topic, const BagVisit* visit) {
    FieldCursor c(records, where + " (inflated)");
    while (!c.at_end()) {
      const std::uint64_t offset = c.offset();
      const auto header = c.bytes(c.u32("record header length"), "record header");
      const auto data = c.bytes(c.u32("record data length"), "record data");
      if (!record(Fields(header, c.name(), offset), data, topic, visit)) return false;
    }
    return true;
  }

  /// A connection or message record; false when `visit` stopped.
  bool record(const Fields& f, std::span<const std::uint8_t> data, const std::string* topic, const BagVisit* visit) {
    const std::uint8_t op = f.op();
    if (op == kBagConnection) {
      const std::uint32_t id = f.u32("conn");
      const Fields header(data, src_->name() + ": connection " + std::to_string(id), 0);
      BagTopic t;
      t.name = f.text("topic");
      t.type = header.text("type");
      t.encoding = MessageEncoding::Ros1;
      t.encoding_name = "ros1";
      connections_[id] = std::move(t);
      return true;
    }
    if (op != kBagMessageData || visit == nullptr) return true;
    const std::uint32_t id = f.u32("conn");
    const auto it = connections_.find(id);
    if (it == connections_.end()) f.fail("message on connection " + std::to_string(id) + " before its connection record");
    if (it->second.name != *topic) return true;
    const auto time = f.fixed("time", 8);
    BagMessage m;
    m.topic = &it->second;
    m.log_time_ns = static_cast<std::int64_t>(load_le32(time.data())) * 1'000'000'000 + load_le32(time.data() + 4);
    m.data = data;
    return (*visit)(m);
  }

  std::unique_ptr<ByteSource> src_;
  BagLimits limits_;
  std::uint64_t index_pos_ = 0;
  std::uint32_t connection_count_ = 0;
  std::map<std::uint32_t, BagTopic> connections_;
};

}  // namespace

std::unique_ptr<BagReader> make_ros1_bag_reader(std::unique_ptr<ByteSource> bytes, BagLimits limits) {
  return std::make_unique<Ros1BagReader>(std::move(bytes), limits);
}

}  // namespace liod::drivers::detail
