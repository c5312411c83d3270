// Fuzz target: the Xsens MTData2 stream parser, fed the bytes a serial port delivers. The same
// stream is parsed whole and in pieces (cut where the bytes say): samples and statistics must not
// depend on how the bytes arrived, and every sample handed to the odometry must be finite.

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "fuzz_support.hpp"
#include "liod/drivers/mtdata2.hpp"

namespace {

using liod::drivers::xsens::MtData2Parser;
using liod::drivers::xsens::MtData2Sample;
using liod::drivers::xsens::MtParserStats;

bool same(const MtData2Sample& a, const MtData2Sample& b) {
  // Bitwise for the vectors: a NaN must compare equal to the same NaN.
  auto same_vec = [](const auto& x, const auto& y) {
    return x.has_value() == y.has_value() && (!x || std::memcmp(x->data(), y->data(), sizeof(double) * 3) == 0);
  };
  return a.packet_counter == b.packet_counter && a.sample_time_fine == b.sample_time_fine &&
         same_vec(a.rate_of_turn, b.rate_of_turn) && same_vec(a.acceleration, b.acceleration);
}

bool same(const MtParserStats& a, const MtParserStats& b) {
  return a.messages == b.messages && a.other_messages == b.other_messages && a.bad_checksum == b.bad_checksum &&
         a.malformed == b.malformed && a.skipped_bytes == b.skipped_bytes && a.counter_gaps == b.counter_gaps;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  const std::span<const std::uint8_t> stream(data, size);

  std::vector<MtData2Sample> whole_samples;
  MtData2Parser whole([&](const MtData2Sample& s) { whole_samples.push_back(s); });
  whole.feed(stream);

  std::vector<MtData2Sample> piece_samples;
  MtData2Parser pieces([&](const MtData2Sample& s) {
    require(!s.rate_of_turn || s.rate_of_turn->allFinite(), "non-finite rate of turn handed out");
    require(!s.acceleration || s.acceleration->allFinite(), "non-finite acceleration handed out");
    piece_samples.push_back(s);
  });
  liod::fuzz::for_each_piece(stream, [&](std::span<const std::uint8_t> piece) { pieces.feed(piece); });

  require(whole_samples.size() == piece_samples.size(), "sample count depends on the chunking");
  for (std::size_t i = 0; i < whole_samples.size(); ++i)
    require(same(whole_samples[i], piece_samples[i]), "a sample depends on the chunking");
  require(same(whole.stats(), pieces.stats()), "statistics depend on the chunking");
  return 0;
}
