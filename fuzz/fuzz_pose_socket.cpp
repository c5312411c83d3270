// Fuzz target: what the pose socket parses from a peer's bytes. The input is a byte stream:
//  - as a client's requests to the server: read whole and in pieces (cut where the bytes say),
//    the resulting mode must not depend on how the bytes arrived;
//  - as the server's stream to a client (pose::decode, used by PoseClient): every message decoded
//    must lie inside the bytes and encode back to the same bytes.

#include <algorithm>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "fuzz_support.hpp"
#include "liod/daemon/pose_protocol.hpp"

namespace {

using namespace liod::pose;
using liod::fuzz::require;

std::string_view as_text(std::span<const std::uint8_t> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

void check_requests(std::span<const std::uint8_t> stream) {
  ClientMode whole_mode;
  RequestReader whole;
  whole.feed(as_text(stream), whole_mode);

  ClientMode piece_mode;
  RequestReader pieces;
  liod::fuzz::for_each_piece(stream, [&](std::span<const std::uint8_t> piece) { pieces.feed(as_text(piece), piece_mode); });
  require(whole_mode.json == piece_mode.json && whole_mode.scan_only == piece_mode.scan_only,
          "the client's mode depends on how its bytes arrived");
}

void check_messages(std::span<const std::uint8_t> stream) {
  Message m;
  std::vector<std::uint8_t> again;
  for (;;) {
    std::size_t used = 0;
    if (decode(stream, m, used) != DecodeStatus::Ok) return;
    require(used >= kHeaderSize && used <= stream.size(), "decoded message length outside the bytes");
    again.clear();
    if (m.type == MessageType::Health) {
      encode_health(m.health, 0, again);
      // Message does not keep a health message's sequence number (bytes 12..15): skip it.
      require(again.size() == used && std::equal(again.begin(), again.begin() + 12, stream.begin()) &&
                  std::equal(again.begin() + kHeaderSize, again.end(), stream.begin() + kHeaderSize),
              "health message does not encode back to its bytes");
    } else {
      encode(m.pose, again);
      constexpr std::size_t kReserved = 4;  // the last field: ignored by decode, written as 0
      require(again.size() == used && std::equal(again.begin(), again.end() - kReserved, stream.begin()),
              "pose message does not encode back to its bytes");
    }
    stream = stream.subspan(used);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> stream(data, size);
  check_requests(stream);
  check_messages(stream);
  return 0;
}
