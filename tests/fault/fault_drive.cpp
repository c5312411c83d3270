#include "fault_drive.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "liod/eval/io.hpp"

namespace liod::test {
namespace {

constexpr const char* kSimArguments = "--route urban --seed 1 --duration 25 --max-speed 12";

/// Holds an exclusive lock on a file for its lifetime: one process generates, the others wait.
class FileLock {
 public:
  explicit FileLock(const std::filesystem::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT, 0644)) {
    if (fd_ >= 0) ::flock(fd_, LOCK_EX);
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);  // releases the lock
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// True when `dir` holds a complete drive made by this liod-sim with these arguments.
bool up_to_date(const std::filesystem::path& dir, const std::filesystem::path& sim) {
  const auto stamp = dir / "complete";
  return std::filesystem::exists(stamp) && read_text(stamp) == kSimArguments &&
         std::filesystem::last_write_time(stamp) > std::filesystem::last_write_time(sim);
}

bool generate(const std::filesystem::path& dir, const std::filesystem::path& sim) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string cmd = "timeout 600 " + sim.string() + " " + kSimArguments + " --quiet --out " + dir.string() + " > " +
                          (dir / "sim.log").string() + " 2>&1";
  if (std::system(cmd.c_str()) != 0) return false;
  std::ofstream(dir / "complete") << kSimArguments;
  return true;
}

}  // namespace

const FaultDrive* fault_drive() {
  static std::unique_ptr<FaultDrive> drive;
  static bool tried = false;
  if (tried) return drive.get();
  tried = true;
  const std::filesystem::path binary_dir = LIOD_BINARY_DIR;
  const auto sim = binary_dir / "bin" / "liod-sim";
  if (!std::filesystem::exists(sim)) return nullptr;
  const auto dir = binary_dir / "test-data" / "fault-drive";
  std::filesystem::create_directories(dir.parent_path());
  {
    FileLock lock(dir.parent_path() / "fault-drive.lock");
    if (!up_to_date(dir, sim) && !generate(dir, sim)) return nullptr;
  }
  auto d = std::make_unique<FaultDrive>();
  d->dir = dir;
  d->recording = fault::read_recording(dir / "lidar.pcap", dir / "imu.csv");
  d->truth = eval::read_tum((dir / "groundtruth.tum").string());
  drive = std::move(d);
  return drive.get();
}

}  // namespace liod::test
