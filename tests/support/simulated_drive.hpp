#pragma once
// Simulated drives shared by every test process. ctest runs each test in a process of its own, so
// a drive made per process would be simulated again for every test that reads it; instead each
// drive is made once into the drive tree (test_env.hpp's drive_tree(): test-data/<name>/) by the
// first process that asks, under a file lock the others wait on, and made again only when
// liod-sim has been rebuilt since or the arguments changed.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "test_env.hpp"

namespace liod::test {

namespace drive_cache {

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

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// What a drive's stamp holds: the liod-sim that made it and its arguments.
inline std::string stamp_text(const std::filesystem::path& sim, const std::string& arguments) {
  return sim.string() + " " + arguments;
}

/// True when `dir` holds a complete drive made by this liod-sim with these arguments.
inline bool up_to_date(const std::filesystem::path& dir, const std::filesystem::path& sim, const std::string& arguments) {
  const auto stamp = dir / "complete";
  return std::filesystem::exists(stamp) && read_text(stamp) == stamp_text(sim, arguments) &&
         std::filesystem::last_write_time(stamp) > std::filesystem::last_write_time(sim);
}

inline bool generate(const std::filesystem::path& dir, const std::filesystem::path& sim, const std::string& arguments) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string cmd = "timeout 600 " + sim.string() + " " + arguments + " --quiet --out " + dir.string() + " > " +
                          (dir / "sim.log").string() + " 2>&1";
  if (std::system(cmd.c_str()) != 0) return false;
  std::ofstream(dir / "complete") << stamp_text(sim, arguments);
  return true;
}

}  // namespace drive_cache

/// The directory of the drive `liod-sim ARGUMENTS` makes, test-data/`name` in the drive tree;
/// empty when liod-sim is not built or failed (its output is then in test-data/`name`/sim.log).
inline std::filesystem::path cached_drive_dir(const std::string& name, const std::string& arguments) {
  const auto sim = sim_program();
  if (!std::filesystem::exists(sim)) return {};
  const auto dir = drive_tree() / "test-data" / name;
  std::filesystem::create_directories(dir.parent_path());
  const drive_cache::FileLock lock(dir.parent_path() / (name + ".lock"));
  if (!drive_cache::up_to_date(dir, sim, arguments) && !drive_cache::generate(dir, sim, arguments)) return {};
  return dir;
}

}  // namespace liod::test
