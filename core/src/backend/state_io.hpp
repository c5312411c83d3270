#pragma once
// Byte-level helpers shared by the persistence units (map_store.cpp, graph_journal.cpp,
// state_writer.cpp): little-endian-as-in-memory encoding, checksums and file primitives. Private
// to liod_backend (not under include/). Named namespace, not an anonymous one: the units are
// compiled together in unity builds, so each helper has exactly one definition (state_io.cpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "liod/backend/map_store.hpp"

namespace liod::state_io {

/// 64-bit FNV-1a over a whole file: detects a torn or bit-flipped file (not an adversary).
std::uint64_t fnv1a(std::string_view bytes);
/// CRC-32 (IEEE 802.3, reflected, as zlib's): per journal record.
std::uint32_t crc32(std::string_view bytes);

std::string errno_text();
std::string read_all(const std::filesystem::path& path);
std::filesystem::path keyframe_path(const std::filesystem::path& dir, std::uint64_t id);
void fsync_directory(const std::filesystem::path& dir);
/// Creates or replaces `path` with `bytes`; `durable`: fsync it.
void write_whole(const std::filesystem::path& path, std::string_view bytes, bool durable);
/// `<path>.tmp`, then rename over `path`; `durable`: fsync the data before the rename and the
/// directory after it.
void write_file(const std::filesystem::path& path, std::string_view bytes, bool durable);

/// Size in bytes of an encoded pose (translation, quaternion x y z w; doubles).
constexpr std::size_t kPoseBytes = 7 * sizeof(double);

class Encoder {
 public:
  template <typename T>
  void put(const T& v) {
    buffer_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void raw(const void* data, std::size_t n) { buffer_.append(static_cast<const char*>(data), n); }
  void pose(const Eigen::Isometry3d& t) {
    const Eigen::Quaterniond q(t.linear());
    for (int i = 0; i < 3; ++i) put(t.translation()(i));
    for (int i = 0; i < 4; ++i) put(q.coeffs()(i));  // x y z w
  }
  void points(const std::vector<Eigen::Vector3f>& p) {
    put(static_cast<std::uint64_t>(p.size()));
    for (const auto& v : p) raw(v.data(), 3 * sizeof(float));
  }
  std::string& bytes() { return buffer_; }
  /// The content followed by its FNV-1a checksum (a whole file).
  std::string finish_file() {
    put(fnv1a(buffer_));
    return std::move(buffer_);
  }

 private:
  std::string buffer_;
};

/// Reads what Encoder wrote; every failure throws StateError naming `path` (and the context).
class Decoder {
 public:
  Decoder(std::string_view bytes, std::filesystem::path path) : bytes_(bytes), path_(std::move(path)), end_(bytes.size()) {}
  [[noreturn]] void fail(const std::string& what) const { throw StateError(path_.string() + ": " + what); }
  /// A whole file: magic, FNV-1a checksum at the end, version. Leaves the reader after the header.
  void check_file(const char (&magic)[8], std::uint32_t version);
  template <typename T>
  T get() {
    T v{};
    take(&v, sizeof(T));
    return v;
  }
  std::uint64_t count();
  Eigen::Isometry3d pose();
  std::vector<Eigen::Vector3f> points();
  void done() const {
    if (offset_ != end_) fail("trailing bytes after the content");
  }

 private:
  void take(void* out, std::size_t n) {
    if (n > end_ - offset_) fail("truncated");
    std::memcpy(out, bytes_.data() + offset_, n);
    offset_ += n;
  }
  std::string_view bytes_;
  std::filesystem::path path_;
  std::size_t offset_ = 0;
  std::size_t end_ = 0;
};

}  // namespace liod::state_io
