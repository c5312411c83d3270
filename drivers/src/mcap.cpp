// MCAP (mcap.dev/spec, major version 0): the magic "\x89MCAP0\r\n", then records of <opcode u8>
// <content length u64><content>, little-endian, strings and byte arrays with a u32 length before
// them. The data section holds Schema (0x03), Channel (0x04) and Message (0x05) records, bare or
// in Chunks (0x06: compression "", "lz4" or "zstd", with the CRC-32 of the inflated records), and
// ends with Data End (0x0F); an optional summary section repeats every Schema and Channel, and the
// Footer (0x02) just before the closing magic says where it starts.

#include <zlib.h>

#include <algorithm>
#include <map>

#include "bag_formats.hpp"
#include "chunk_compression.hpp"
#include "field_cursor.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers::detail {
namespace {

enum McapOp : std::uint8_t {
  kMcapFooter = 0x02, kMcapSchema = 0x03, kMcapChannel = 0x04, kMcapMessage = 0x05, kMcapChunk = 0x06, kMcapDataEnd = 0x0F
};
constexpr std::uint64_t kMagicBytes = 8;
constexpr std::uint64_t kRecordHead = 9;  // opcode + content length
constexpr std::uint64_t kFooterBytes = kRecordHead + 20;

using McapVisit = std::function<bool(const BagMessage&)>;

class McapReader : public BagReader {
 public:
  McapReader(std::unique_ptr<ByteSource> bytes, BagLimits limits) : src_(std::move(bytes)), limits_(limits) {}

  const char* format() const override { return "MCAP"; }

  std::vector<BagTopic> topics() override {
    if (!read_summary()) walk(nullptr, nullptr);
    std::vector<BagTopic> all;
    for (const auto& entry : channels_) all.push_back(entry.second);
    return distinct_topics(all);
  }

  void read(const std::string& topic, const McapVisit& visit) override { walk(&topic, &visit); }

 private:
  /// The summary's Schema and Channel records; false when the file has no summary.
  bool read_summary() {
    const std::uint64_t size = src_->size();
    if (size < 2 * kMagicBytes + kFooterBytes) return false;
    const std::uint64_t footer = size - kMagicBytes - kFooterBytes;
    const auto bytes = read_range(*src_, footer, kFooterBytes, "footer");
    if (bytes[0] != kMcapFooter || load_le64(&bytes[1]) != 20) return false;  // cut short: no footer
    const std::uint64_t start = load_le64(&bytes[9]);
    const std::uint64_t offsets = load_le64(&bytes[17]);
    if (start == 0) return false;
    const std::uint64_t end = offsets != 0 ? offsets : footer;
    if (start < kMagicBytes || end > footer || start > end) {
      throw InputError(src_->name(), 0, "footer: summary section [" + std::to_string(start) + ", " + std::to_string(end) + ") not in the file");
    }
    for (std::uint64_t pos = start; pos < end;) {
      if (end - pos < kRecordHead) throw InputError(src_->name(), 0, "summary section ends inside a record");
      const auto head = read_range(*src_, pos, kRecordHead, "record");
      const std::uint64_t length = load_le64(&head[1]);
      if (head[0] == kMcapSchema || head[0] == kMcapChannel) {
        const auto content = read_range(*src_, pos + kRecordHead, length, "record");
        record(head[0], content, src_->name(), pos + kRecordHead, nullptr, nullptr);
      } else if (length > end - pos - kRecordHead) {
        read_range(*src_, pos + kRecordHead, length, "summary record");  // throws
      }
      pos += kRecordHead + length;
    }
    return true;
  }

  /// Reads the data section from the start; false when `visit` stopped.
  bool walk(const std::string* topic, const McapVisit* visit) {
    std::uint64_t pos = kMagicBytes;
    while (true) {
      if (src_->size() - pos < kRecordHead) {
        throw InputError(src_->name(), 0, "ends at byte " + std::to_string(src_->size()) +
                                              " without a Data End or Footer record: cut short (`mcap recover` repairs such files)");
      }
      const auto head = read_range(*src_, pos, kRecordHead, "record");
      const std::uint8_t op = head[0];
      const std::uint64_t length = load_le64(&head[1]);
      if (op == kMcapDataEnd || op == kMcapFooter) return true;
      if (op == kMcapSchema || op == kMcapChannel || op == kMcapMessage || op == kMcapChunk) {
        const auto content = read_range(*src_, pos + kRecordHead, length, "record");
        const bool go_on = op == kMcapChunk ? chunk(content, pos, topic, visit)
                                        : record(op, content, src_->name(), pos + kRecordHead, topic, visit);
        if (!go_on) return false;
      } else if (length > src_->size() - pos - kRecordHead) {
        read_range(*src_, pos + kRecordHead, length, "record");  // throws: past the end
      }
      pos += kRecordHead + length;
    }
  }

  bool chunk(std::span<const std::uint8_t> content, std::uint64_t pos, const std::string* topic, const McapVisit* visit) {
    const std::string where = src_->name() + ": chunk at byte offset " + std::to_string(pos);
    FieldCursor c(content, where, pos + kRecordHead);
    c.skip(16, "message start and end time");
    const std::uint64_t size = c.u64("uncompressed size");
    const std::uint32_t crc = c.u32("uncompressed CRC");
    const std::string compression = c.string("compression");
    const auto stored = c.bytes(c.u64("records length"), "records");
    if (size > limits_.max_chunk_bytes) c.fail("chunk of " + std::to_string(size) + " bytes, more than the limit");
    Codec codec = Codec::None;
    if (compression == "lz4") codec = Codec::Lz4Frame;
    else if (compression == "zstd") codec = Codec::Zstd;
    else if (!compression.empty()) c.fail("chunk compression '" + compression + "' (expected \"\", lz4 or zstd)");
    const std::vector<std::uint8_t> records = inflate(codec, stored, size, where);
    if (crc != 0) {
      uLong actual = ::crc32(0L, Z_NULL, 0);
      for (std::size_t done = 0; done < records.size();) {  // zlib counts in uInt
        const auto n = static_cast<uInt>(std::min<std::size_t>(records.size() - done, 1U << 30));
        actual = ::crc32(actual, records.data() + done, n);
        done += n;
      }
      if (actual != crc) c.fail("the inflated records fail their CRC-32: corrupt");
    }
    FieldCursor r(records, where + " (inflated)");
    while (!r.at_end()) {
      const std::uint8_t op = r.u8("opcode");
      const std::uint64_t length = r.u64("record length");
      const std::uint64_t offset = r.offset();
      const auto inner = r.bytes(length, "record");
      if (!record(op, inner, r.name(), offset, topic, visit)) return false;
    }
    return true;
  }

  /// A Schema, Channel or Message record (others are skipped); false when `visit` stopped.
  bool record(std::uint8_t op, std::span<const std::uint8_t> content, const std::string& name, std::uint64_t offset,
              const std::string* topic, const McapVisit* visit) {
    FieldCursor c(content, name, offset);
    if (op == kMcapSchema) {
      const std::uint16_t id = c.u16("schema id");
      schemas_[id] = c.string("schema name");
      return true;
    }
    if (op == kMcapChannel) {
      const std::uint16_t id = c.u16("channel id");
      const std::uint16_t schema = c.u16("schema id");
      BagTopic t;
      t.name = c.string("topic");
      t.encoding_name = c.string("message encoding");
      t.encoding = t.encoding_name == "cdr" ? MessageEncoding::Cdr : t.encoding_name == "ros1" ? MessageEncoding::Ros1 : MessageEncoding::Other;
      if (schema != 0) {
        const auto s = schemas_.find(schema);
        if (s == schemas_.end()) c.fail("channel " + std::to_string(id) + " before its schema " + std::to_string(schema));
        t.type = s->second;
      }
      channels_[id] = std::move(t);
      return true;
    }
    if (op != kMcapMessage || visit == nullptr) return true;
    const std::uint16_t id = c.u16("channel id");
    const auto it = channels_.find(id);
    if (it == channels_.end()) c.fail("message on channel " + std::to_string(id) + " before its Channel record");
    if (it->second.name != *topic) return true;
    c.skip(4, "sequence");
    BagMessage m;
    m.topic = &it->second;
    m.log_time_ns = static_cast<std::int64_t>(c.u64("log time"));
    c.skip(8, "publish time");
    m.data = c.bytes(c.remaining(), "data");
    return (*visit)(m);
  }

  std::unique_ptr<ByteSource> src_;
  BagLimits limits_;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, BagTopic> channels_;
};

}  // namespace

std::unique_ptr<BagReader> make_mcap_reader(std::unique_ptr<ByteSource> bytes, BagLimits limits) {
  return std::make_unique<McapReader>(std::move(bytes), limits);
}

}  // namespace liod::drivers::detail
