#include "state_io.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <fstream>
#include <iterator>

namespace liod::state_io {
namespace fs = std::filesystem;

namespace {
// Guards against a corrupt count asking for an absurd allocation.
constexpr std::uint64_t kMaxCount = 1ULL << 28;

std::array<std::uint32_t, 256> crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1U) != 0 ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
}  // namespace

std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::uint32_t crc32(std::string_view bytes) {
  static const std::array<std::uint32_t, 256> table = crc_table();
  std::uint32_t c = 0xFFFFFFFFU;
  for (unsigned char b : bytes) c = table[(c ^ b) & 0xFFU] ^ (c >> 8);
  return c ^ 0xFFFFFFFFU;
}

std::string errno_text() { return std::strerror(errno); }

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StateError(path.string() + ": cannot open (" + errno_text() + ")");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

fs::path keyframe_path(const fs::path& dir, std::uint64_t id) { return dir / "keyframes" / (std::to_string(id) + ".kf"); }

void fsync_directory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw StateError(dir.string() + ": cannot open directory for fsync (" + errno_text() + ")");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw StateError(dir.string() + ": fsync of the directory failed (" + errno_text() + ")");
}

void write_whole(const fs::path& path, std::string_view bytes, bool durable) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw StateError(path.string() + ": cannot create (" + errno_text() + ")");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = errno_text();
      ::close(fd);
      throw StateError(path.string() + ": write failed (" + why + ")");
    }
    done += static_cast<std::size_t>(n);
  }
  if (durable && ::fsync(fd) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw StateError(path.string() + ": fsync failed (" + why + ")");
  }
  ::close(fd);
}

void write_file(const fs::path& path, std::string_view bytes, bool durable) {
  const fs::path temp = path.string() + ".tmp";
  // Data on disk before the rename makes it visible; the directory fsync makes the rename durable.
  write_whole(temp, bytes, durable);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    throw StateError(path.string() + ": rename from the temp file failed (" + errno_text() + ")");
  }
  if (durable) fsync_directory(path.has_parent_path() ? path.parent_path() : fs::path("."));
}

void Decoder::check_file(const char (&magic)[8], std::uint32_t version) {
  if (bytes_.size() < 8 + 8 + 8 || std::memcmp(bytes_.data(), magic, 8) != 0) {
    fail("not a liod state file (bad magic or truncated)");
  }
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes_.data() + bytes_.size() - 8, 8);
  if (stored != fnv1a(bytes_.substr(0, bytes_.size() - 8))) {
    fail("checksum mismatch: the file is corrupt or was partially written");
  }
  end_ = bytes_.size() - 8;
  offset_ = 8;
  const auto found = get<std::uint32_t>();
  if (found != version) {
    fail("unsupported version " + std::to_string(found) + " (this liod reads " + std::to_string(version) + ")");
  }
  (void)get<std::uint32_t>();
}

std::uint64_t Decoder::count() {
  const auto n = get<std::uint64_t>();
  if (n > kMaxCount) fail("implausible element count " + std::to_string(n));
  return n;
}

Eigen::Isometry3d Decoder::pose() {
  Eigen::Vector3d t;
  Eigen::Quaterniond q;
  for (int i = 0; i < 3; ++i) t(i) = get<double>();
  for (int i = 0; i < 4; ++i) q.coeffs()(i) = get<double>();
  if (!t.allFinite() || !q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6) fail("invalid pose");
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = q.normalized().toRotationMatrix();
  out.translation() = t;
  return out;
}

std::vector<Eigen::Vector3f> Decoder::points() {
  const auto n = count();
  if (n * 3 * sizeof(float) > end_ - offset_) fail("truncated point list");
  std::vector<Eigen::Vector3f> out(n);
  for (auto& p : out) take(p.data(), 3 * sizeof(float));
  return out;
}

}  // namespace liod::state_io
