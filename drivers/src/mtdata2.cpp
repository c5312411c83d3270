#include "liod/drivers/mtdata2.hpp"

#include <bit>

#include "liod/drivers/byte_order.hpp"

namespace liod::drivers::xsens {
namespace {

constexpr std::size_t kMaxMessage = 2048;  // MTData2 messages are well below this

Eigen::Vector3d vec3(const std::uint8_t* p) {
  return {static_cast<double>(std::bit_cast<float>(load_be32(p))), static_cast<double>(std::bit_cast<float>(load_be32(p + 4))),
          static_cast<double>(std::bit_cast<float>(load_be32(p + 8)))};
}

void put_item(std::vector<std::uint8_t>& m, std::uint16_t id, std::span<const std::uint8_t> payload) {
  m.push_back(static_cast<std::uint8_t>(id >> 8));
  m.push_back(static_cast<std::uint8_t>(id));
  m.push_back(static_cast<std::uint8_t>(payload.size()));
  m.insert(m.end(), payload.begin(), payload.end());
}

}  // namespace

void MtData2Parser::feed(std::span<const std::uint8_t> bytes) {
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
  parse_buffer();
}

void MtData2Parser::parse_buffer() {
  std::size_t pos = 0;
  const std::size_t n = buffer_.size();
  while (pos < n) {
    if (buffer_[pos] != kPreamble) {
      ++pos;
      ++stats_.skipped_bytes;
      continue;
    }
    if (n - pos < 4) break;  // need PRE BID MID LEN
    // A preamble followed by a wrong bus id cannot start a message: skip this byte only.
    if (buffer_[pos + 1] != kBusId) {
      ++pos;
      ++stats_.skipped_bytes;
      continue;
    }
    std::size_t header = 4;
    std::size_t length = buffer_[pos + 3];
    if (length == 0xFF) {
      if (n - pos < 6) break;
      length = load_be16(&buffer_[pos + 4]);
      header = 6;
    }
    if (header + length + 1 > kMaxMessage) {  // implausible: a false preamble
      ++pos;
      ++stats_.skipped_bytes;
      continue;
    }
    const std::size_t total = header + length + 1;
    if (n - pos < total) break;  // wait for the rest (a truncated message is found out by the next preamble's checksum)
    std::uint8_t sum = 0;
    for (std::size_t i = pos + 1; i < pos + total; ++i) sum = static_cast<std::uint8_t>(sum + buffer_[i]);
    if (sum != 0) {
      // Corrupt, or a preamble byte inside data / a message cut short by the one after it:
      // resynchronise from the next byte rather than jumping over `total` bytes.
      ++stats_.bad_checksum;
      ++pos;
      continue;
    }
    const std::uint8_t mid = buffer_[pos + 2];
    if (mid == kMidMtData2) {
      MtData2Sample sample;
      if (decode_payload(std::span(buffer_).subspan(pos + header, length), sample)) {
        ++stats_.messages;
        if (sample.packet_counter) {
          if (last_counter_) {
            const auto step = static_cast<std::uint16_t>(*sample.packet_counter - *last_counter_);
            if (step > 1 && step < 0x8000) stats_.counter_gaps += step - 1U;
          }
          last_counter_ = sample.packet_counter;
        }
        on_sample_(sample);
      } else {
        ++stats_.malformed;
      }
    } else {
      ++stats_.other_messages;
    }
    pos += total;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(pos));
  if (buffer_.size() > 4 * kMaxMessage) {  // cannot happen with the checks above; a safety bound
    stats_.skipped_bytes += buffer_.size();
    buffer_.clear();
  }
}

bool MtData2Parser::decode_payload(std::span<const std::uint8_t> d, MtData2Sample& out) const {
  std::size_t i = 0;
  while (i < d.size()) {
    if (d.size() - i < 3) return false;
    const std::uint16_t id = load_be16(&d[i]);
    const std::size_t size = d[i + 2];
    i += 3;
    if (d.size() - i < size) return false;
    const std::uint8_t* p = &d[i];
    switch (id) {
      case kPacketCounter:
        if (size == 2) out.packet_counter = load_be16(p);
        break;
      case kSampleTimeFine:
        if (size == 4) out.sample_time_fine = load_be32(p);
        break;
      // A NaN or infinity here is corruption the 8-bit checksum let through (1 in 256 corrupt
      // messages pass it); handed on, it would poison the filter state for good.
      case kRateOfTurn:
        if (size == 12) out.rate_of_turn = vec3(p);
        if (out.rate_of_turn && !out.rate_of_turn->allFinite()) return false;
        break;
      case kAcceleration:
        if (size == 12) out.acceleration = vec3(p);
        if (out.acceleration && !out.acceleration->allFinite()) return false;
        break;
      case kStatusWord:
        if (size == 4) out.status_word = load_be32(p);
        break;
      default:
        break;  // FreeAcceleration and everything else: skipped by size
    }
    i += size;
  }
  return true;
}

std::vector<std::uint8_t> build_xbus_message(std::uint8_t mid, const std::vector<std::uint8_t>& data) {
  std::vector<std::uint8_t> m{kPreamble, kBusId, mid};
  if (data.size() < 0xFF) {
    m.push_back(static_cast<std::uint8_t>(data.size()));
  } else {
    m.push_back(0xFF);
    m.push_back(static_cast<std::uint8_t>(data.size() >> 8));
    m.push_back(static_cast<std::uint8_t>(data.size()));
  }
  m.insert(m.end(), data.begin(), data.end());
  std::uint8_t sum = 0;
  for (std::size_t i = 1; i < m.size(); ++i) sum = static_cast<std::uint8_t>(sum + m[i]);
  m.push_back(static_cast<std::uint8_t>(0x100 - sum));
  return m;
}

std::vector<std::uint8_t> build_mtdata2(std::uint16_t counter, std::uint32_t fine, const Eigen::Vector3d& gyro,
                                        const Eigen::Vector3d& accel, std::optional<std::uint32_t> status_word) {
  std::vector<std::uint8_t> data;
  std::uint8_t b[12];
  store_be16(b, counter);
  put_item(data, kPacketCounter, std::span(b, 2));
  store_be32(b, fine);
  put_item(data, kSampleTimeFine, std::span(b, 4));
  for (int k = 0; k < 3; ++k) store_be32(b + 4 * k, std::bit_cast<std::uint32_t>(static_cast<float>(gyro[k])));
  put_item(data, kRateOfTurn, std::span(b, 12));
  for (int k = 0; k < 3; ++k) store_be32(b + 4 * k, std::bit_cast<std::uint32_t>(static_cast<float>(accel[k])));
  put_item(data, kAcceleration, std::span(b, 12));
  if (status_word) {
    store_be32(b, *status_word);
    put_item(data, kStatusWord, std::span(b, 4));
  }
  return build_xbus_message(kMidMtData2, data);
}

}  // namespace liod::drivers::xsens
