#include "liod/drivers/bag_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "bag_formats.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

class FileBytes : public ByteSource {
 public:
  explicit FileBytes(const std::filesystem::path& path) : name_(path.string()), fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {
    if (fd_ < 0) throw InputError(name_, 0, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw InputError(name_, 0, "not a regular file");
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~FileBytes() override { ::close(fd_); }
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;

  std::uint64_t size() const override { return size_; }
  const std::string& name() const override { return name_; }
  void read(std::uint64_t offset, std::span<std::uint8_t> out) const override {
    if (offset > size_ || out.size() > size_ - offset) throw InputError(name_, 0, "read past the end of the file");
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t n = ::pread(fd_, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw InputError(name_, 0, n == 0 ? "file shrank while read" : std::string("read failed: ") + std::strerror(errno));
      done += static_cast<std::size_t>(n);
    }
  }

 private:
  std::string name_;
  int fd_;
  std::uint64_t size_ = 0;
};

class MemoryBytes : public ByteSource {
 public:
  MemoryBytes(std::span<const std::uint8_t> bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {}
  std::uint64_t size() const override { return bytes_.size(); }
  const std::string& name() const override { return name_; }
  void read(std::uint64_t offset, std::span<std::uint8_t> out) const override {
    if (offset > bytes_.size() || out.size() > bytes_.size() - offset) throw InputError(name_, 0, "read past the end of the input");
    std::copy_n(bytes_.begin() + static_cast<std::ptrdiff_t>(offset), out.size(), out.begin());
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::string name_;
};

constexpr std::string_view kRosbagMagic = "#ROSBAG V";
constexpr std::uint8_t kMcapMagic[] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

}  // namespace

namespace detail {

std::vector<std::uint8_t> read_range(const ByteSource& source, std::uint64_t offset, std::uint64_t n, const std::string& what) {
  if (offset > source.size() || n > source.size() - offset) {
    throw InputError(source.name(), 0, what + " at byte offset " + std::to_string(offset) + " claims " + std::to_string(n) +
                                           " bytes, past the end of the file (" + std::to_string(source.size()) +
                                           " bytes): cut short or corrupt");
  }
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(n));
  source.read(offset, bytes);
  return bytes;
}

std::vector<BagTopic> distinct_topics(const std::vector<BagTopic>& all) {
  std::vector<BagTopic> out;
  for (const BagTopic& t : all) {
    const bool seen = std::any_of(out.begin(), out.end(), [&](const BagTopic& o) { return o.name == t.name && o.type == t.type; });
    if (!seen) out.push_back(t);
  }
  return out;
}

}  // namespace detail

std::unique_ptr<ByteSource> open_file_bytes(const std::filesystem::path& path) { return std::make_unique<FileBytes>(path); }

std::unique_ptr<ByteSource> memory_bytes(std::span<const std::uint8_t> bytes, std::string name) {
  return std::make_unique<MemoryBytes>(bytes, std::move(name));
}

std::unique_ptr<BagReader> open_bag(std::unique_ptr<ByteSource> bytes, BagLimits limits) {
  std::uint8_t head[13] = {};
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(bytes->size(), sizeof head));
  bytes->read(0, std::span<std::uint8_t>(head, n));
  const std::string_view text(reinterpret_cast<const char*>(head), n);
  if (text.substr(0, kRosbagMagic.size()) == kRosbagMagic) {
    if (text != "#ROSBAG V2.0\n") {
      throw InputError(bytes->name(), 0, "a ROS bag of version '" + std::string(text.substr(kRosbagMagic.size(), 3)) +
                                             "': only format 2.0 (ROS 1 since C Turtle) is read");
    }
    return detail::make_ros1_bag_reader(std::move(bytes), limits);
  }
  if (n >= sizeof kMcapMagic && std::equal(std::begin(kMcapMagic), std::end(kMcapMagic), head)) {
    return detail::make_mcap_reader(std::move(bytes), limits);
  }
  throw InputError(bytes->name(), 0, "neither a ROS 1 bag (\"#ROSBAG V2.0\") nor an MCAP file (\"\\x89MCAP0\\r\\n\")");
}

std::unique_ptr<BagReader> open_bag(const std::filesystem::path& path) { return open_bag(open_file_bytes(path)); }

std::string describe_topics(const std::vector<BagTopic>& topics) {
  if (topics.empty()) return "  (no topics)\n";
  std::string s;
  for (const auto& t : topics) s += "  " + t.name + " (" + (t.type.empty() ? "no type" : t.type) + ", " + t.encoding_name + ")\n";
  return s;
}

}  // namespace liod::drivers
