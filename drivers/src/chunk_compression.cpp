#include "chunk_compression.hpp"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <memory>

#include "liod/drivers/input_error.hpp"

namespace liod::drivers::detail {
namespace {

/// The output buffer: starts small and doubles, never past `size`.
class Output {
 public:
  explicit Output(std::uint64_t size) : size_(size) { buffer_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size, 1 << 16))); }
  /// Room to write into; empty once `size` bytes are written.
  std::span<std::uint8_t> room() {
    if (written_ == buffer_.size() && buffer_.size() < size_) {
      buffer_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size_, 2 * static_cast<std::uint64_t>(buffer_.size()))));
    }
    return std::span<std::uint8_t>(buffer_).subspan(written_);
  }
  void wrote(std::size_t n) { written_ += n; }
  [[nodiscard]] std::size_t written() const { return written_; }
  std::vector<std::uint8_t> take() {
    buffer_.resize(written_);
    return std::move(buffer_);
  }

 private:
  std::uint64_t size_;
  std::vector<std::uint8_t> buffer_;
  std::size_t written_ = 0;
};

[[noreturn]] void fail(const std::string& name, const char* codec, const std::string& why) {
  throw InputError(name, 0, std::string(codec) + " chunk: " + why);
}

std::vector<std::uint8_t> bunzip2(std::span<const std::uint8_t> in, std::uint64_t size, const std::string& name) {
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) fail(name, "bz2", "cannot start the decompressor");
  const std::unique_ptr<bz_stream, int (*)(bz_stream*)> end(&s, BZ2_bzDecompressEnd);
  Output out(size);
  // bzlib counts in unsigned int: fed in pieces below 4 GiB.
  constexpr std::size_t kStep = std::size_t{1} << 30;
  std::size_t fed = 0;
  int rc = BZ_OK;
  while (rc == BZ_OK) {
    if (s.avail_in == 0 && fed < in.size()) {
      const std::size_t n = std::min(kStep, in.size() - fed);
      s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data() + fed));  // bzlib's API is not const
      s.avail_in = static_cast<unsigned>(n);
      fed += n;
    }
    const auto room = out.room();
    if (room.empty()) fail(name, "bz2", "inflates to more than the " + std::to_string(size) + " bytes stated");
    const std::size_t n = std::min(kStep, room.size());
    s.next_out = reinterpret_cast<char*>(room.data());
    s.avail_out = static_cast<unsigned>(n);
    const unsigned before_in = s.avail_in;
    rc = BZ2_bzDecompress(&s);
    out.wrote(n - s.avail_out);
    if (rc == BZ_OK && s.avail_in == before_in && s.avail_out == n && fed == in.size()) break;  // no progress: cut short
  }
  if (rc != BZ_STREAM_END) {
    fail(name, "bz2", rc == BZ_OK ? "the data ends before the bzip2 stream does" : "corrupt bzip2 data (bzlib error " + std::to_string(rc) + ")");
  }
  if (out.written() != size) fail(name, "bz2", "inflates to " + std::to_string(out.written()) + " bytes, not the " + std::to_string(size) + " stated");
  return out.take();
}

std::vector<std::uint8_t> unlz4(std::span<const std::uint8_t> in, std::uint64_t size, const std::string& name) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) fail(name, "lz4", "cannot start the decompressor");
  const std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> end(ctx, LZ4F_freeDecompressionContext);
  Output out(size);
  std::size_t pos = 0;
  while (true) {
    const auto room = out.room();
    std::size_t out_n = room.size();
    std::size_t in_n = in.size() - pos;
    const std::size_t hint = LZ4F_decompress(ctx, room.data(), &out_n, in.data() + pos, &in_n, nullptr);
    if (LZ4F_isError(hint)) fail(name, "lz4", std::string("corrupt LZ4 frame: ") + LZ4F_getErrorName(hint));
    pos += in_n;
    out.wrote(out_n);
    if (hint == 0) break;  // the frame is complete
    if (in_n == 0 && out_n == 0) {
      fail(name, "lz4", room.empty() ? "inflates to more than the " + std::to_string(size) + " bytes stated"
                                     : std::string("the data ends before the LZ4 frame does"));
    }
  }
  if (pos != in.size()) fail(name, "lz4", "data after the end of the LZ4 frame");
  if (out.written() != size) fail(name, "lz4", "inflates to " + std::to_string(out.written()) + " bytes, not the " + std::to_string(size) + " stated");
  return out.take();
}

std::vector<std::uint8_t> unzstd(std::span<const std::uint8_t> in, std::uint64_t size, const std::string& name) {
  ZSTD_DStream* ds = ZSTD_createDStream();
  if (ds == nullptr) fail(name, "zstd", "cannot start the decompressor");
  const std::unique_ptr<ZSTD_DStream, std::size_t (*)(ZSTD_DStream*)> end(ds, ZSTD_freeDStream);
  Output out(size);
  ZSTD_inBuffer input{in.data(), in.size(), 0};
  std::size_t hint = 1;
  while (hint != 0) {
    const auto room = out.room();
    ZSTD_outBuffer output{room.data(), room.size(), 0};
    const std::size_t in_before = input.pos;
    hint = ZSTD_decompressStream(ds, &output, &input);
    if (ZSTD_isError(hint)) fail(name, "zstd", std::string("corrupt Zstandard data: ") + ZSTD_getErrorName(hint));
    out.wrote(output.pos);
    if (hint != 0 && output.pos == 0 && input.pos == in_before) {
      fail(name, "zstd", room.empty() ? "inflates to more than the " + std::to_string(size) + " bytes stated"
                                      : std::string("the data ends before the Zstandard frame does"));
    }
  }
  if (input.pos != input.size) fail(name, "zstd", "data after the end of the Zstandard frame");
  if (out.written() != size) fail(name, "zstd", "inflates to " + std::to_string(out.written()) + " bytes, not the " + std::to_string(size) + " stated");
  return out.take();
}

}  // namespace

std::vector<std::uint8_t> inflate(Codec codec, std::span<const std::uint8_t> compressed, std::uint64_t size,
                                  const std::string& name) {
  switch (codec) {
    case Codec::None:
      if (compressed.size() != size) {
        throw InputError(name, 0, "uncompressed chunk of " + std::to_string(compressed.size()) + " bytes states " + std::to_string(size));
      }
      return {compressed.begin(), compressed.end()};
    case Codec::Bz2: return bunzip2(compressed, size, name);
    case Codec::Lz4Frame: return unlz4(compressed, size, name);
    case Codec::Zstd: return unzstd(compressed, size, name);
  }
  return {};
}

}  // namespace liod::drivers::detail
