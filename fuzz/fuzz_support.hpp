#pragma once
// Shared by the fuzz targets: a broken invariant reported as a crash, the fuzz input as a file
// for the readers that take a path, and a deterministic cutting of a byte stream into pieces.

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>

namespace liod::fuzz {

/// Aborts with `what` when `ok` is false, so libFuzzer keeps the input as a crash.
inline void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}

/// Where touch() leaves its result, so the compiler cannot drop the reads.
inline volatile std::uint8_t touched = 0;

/// Reads every byte, so that AddressSanitizer checks `bytes` lies in memory the caller may read.
inline void touch(std::span<const std::uint8_t> bytes) {
  std::uint8_t x = 0;
  for (const std::uint8_t b : bytes) x = static_cast<std::uint8_t>(x ^ b);
  touched = x;
}

/// The fuzz input as an in-memory file (memfd): path() opens like any file, no disk involved.
class MemoryFile {
 public:
  MemoryFile(const std::uint8_t* data, std::size_t size) : fd_(::memfd_create("liod-fuzz", MFD_CLOEXEC)) {
    require(fd_ >= 0, "memfd_create failed");
    while (size > 0) {
      const ssize_t n = ::write(fd_, data, size);
      require(n > 0, "write to memfd failed");
      data += n;
      size -= static_cast<std::size_t>(n);
    }
  }
  ~MemoryFile() { ::close(fd_); }
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;

  [[nodiscard]] std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

/// Calls `piece` on consecutive pieces of `bytes` whose lengths (1..64) the bytes themselves pick:
/// a stateful parser then sees the same stream cut at many places as the input mutates.
template <typename Piece>
void for_each_piece(std::span<const std::uint8_t> bytes, Piece&& piece) {
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    const std::size_t n = std::min<std::size_t>(1 + bytes[pos] % 64, bytes.size() - pos);
    piece(bytes.subspan(pos, n));
    pos += n;
  }
}

}  // namespace liod::fuzz
