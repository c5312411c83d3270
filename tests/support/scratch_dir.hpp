#pragma once
// A test's scratch directory: fresh under the system's temporary directory, and removed with
// everything in it when it goes out of scope (a function-local static one when the test program
// exits), so that test runs leave nothing behind in /tmp.
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <system_error>

namespace liod::test {

class ScratchDir {
 public:
  /// <temp>/liod-test-<name>-<pid>-<n>, n counting this process's scratch directories; emptied
  /// first if a killed run left it.
  explicit ScratchDir(const std::string& name = "scratch")
      : path_(std::filesystem::temp_directory_path() /
              ("liod-test-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(next_number()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  ScratchDir(ScratchDir&&) = delete;
  ScratchDir& operator=(ScratchDir&&) = delete;

  // No conversion to a path: a temporary converted to one would remove the directory at once.
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }
  [[nodiscard]] std::string string() const { return path_.string(); }

 private:
  static int next_number() {
    static std::atomic<int> made{0};
    return made++;
  }

  std::filesystem::path path_;
};

/// The test program's own scratch directory, removed when the program exits: where helpers that
/// hand out files or directories by name put them.
inline const ScratchDir& program_scratch_dir() {
  static const ScratchDir dir("program");
  return dir;
}

}  // namespace liod::test
