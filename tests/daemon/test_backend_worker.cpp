// The backend worker's keyframe scratch directory: a daemon killed with SIGKILL cannot remove
// its own, so the next start removes those whose process is gone, and leaves a live one's alone.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "liod/daemon/backend_worker.hpp"
#include "test_support.hpp"

using namespace liod;

namespace {

/// A process id that was in use a moment ago and no longer is.
pid_t finished_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

void touch(const std::filesystem::path& file) { std::ofstream(file) << "keyframe cloud"; }

}  // namespace

TEST(BackendWorker, RemovesScratchOfKilledProcessesOnly) {
  namespace fs = std::filesystem;
  const test::ScratchDir scratch("backend-scratch");
  const fs::path& state = scratch.path();
  const fs::path dead = state / ("scratch-" + std::to_string(finished_pid()));
  const fs::path alive = state / ("scratch-" + std::to_string(::getppid()));  // the test runner
  const fs::path unrelated = state / "scratch-notes";
  for (const auto& dir : {dead, alive, unrelated}) {
    fs::create_directories(dir);
    touch(dir / "kf-1.bin");
  }
  Config config;
  config.output.state_dir = state.string();
  config.backend.enabled = true;
  config.backend.persist = false;
  config.backend.memory_keyframes = 10;
  {
    BackendWorker worker(config);
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_TRUE(fs::exists(alive / "kf-1.bin"));
    EXPECT_TRUE(fs::exists(unrelated / "kf-1.bin"));
    EXPECT_TRUE(fs::is_directory(state / ("scratch-" + std::to_string(::getpid()))));  // its own
  }
  EXPECT_FALSE(fs::exists(state / ("scratch-" + std::to_string(::getpid()))));  // removed at exit
  fs::remove_all(state);
}
