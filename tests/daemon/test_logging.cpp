// Log lines under systemd carry sd-daemon(3) priority prefixes ("<3>"), which journald parses
// into the entry's priority (`journalctl -p err`); elsewhere they are plain timestamped lines.
// Whether stderr is the journal is JOURNAL_STREAM's "device:inode" compared with stderr's own
// (systemd.exec(5)): a variable inherited by a process whose stderr was redirected elsewhere
// must not turn its file into one full of prefixes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "liod/daemon/logging.hpp"
#include "reference_replay.hpp"

namespace {

enum class Stream { kThisStderr, kAnotherFile, kUnset };

/// What a child process that sets up logging with stderr on `file` writes there.
std::string log_lines(const std::filesystem::path& file, Stream stream) {
  const pid_t child = ::fork();
  if (child == 0) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0 || ::dup2(fd, STDERR_FILENO) < 0) ::_exit(2);
    struct stat st {};
    ::fstat(STDERR_FILENO, &st);
    char value[64];
    std::snprintf(value, sizeof value, "%llu:%llu", static_cast<unsigned long long>(st.st_dev),
                  static_cast<unsigned long long>(stream == Stream::kThisStderr ? st.st_ino : st.st_ino + 1));
    if (stream == Stream::kUnset) ::unsetenv("JOURNAL_STREAM");
    else ::setenv("JOURNAL_STREAM", value, 1);
    liod::setup_logging("debug");
    spdlog::debug("a debug line");
    spdlog::info("an info line");
    spdlog::warn("a warning");
    spdlog::error("an error");
    spdlog::critical("a critical one");
    spdlog::default_logger()->flush();
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  return liod::test::slurp(file);
}

}  // namespace

TEST(Logging, JournalGetsPriorityPrefixes) {
  const liod::test::ScratchDir dir("logging");
  EXPECT_EQ(log_lines(dir / "err.txt", Stream::kThisStderr),
            "<7>a debug line\n<6>an info line\n<4>a warning\n<3>an error\n<2>a critical one\n");
}

TEST(Logging, ElsewhereLinesArePlain) {
  const liod::test::ScratchDir dir("logging");
  for (const Stream s : {Stream::kAnotherFile, Stream::kUnset}) {
    const std::string out = log_lines(dir / "err.txt", s);
    EXPECT_EQ(out.find('<'), std::string::npos) << out;
    EXPECT_NE(out.find(" error an error\n"), std::string::npos) << out;
    EXPECT_NE(out.find(" warning a warning\n"), std::string::npos) << out;
  }
}
