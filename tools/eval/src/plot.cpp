#include "liod/eval/plot.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <vector>

#include "liod/eval/io.hpp"

extern char** environ;

namespace liod::eval {
namespace {

/// A temporary file, removed when the object goes (also when the plot throws).
class TempFile {
 public:
  explicit TempFile(const std::string& suffix) {
    std::string pattern = (std::filesystem::temp_directory_path() / "liod-eval-XXXXXX").string() + suffix;
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    const int fd = mkstemps(name.data(), static_cast<int>(suffix.size()));
    if (fd < 0) throw std::runtime_error("cannot create a temporary file: " + std::string(std::strerror(errno)));
    ::close(fd);
    path_ = name.data();
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Runs argv[0] with the arguments (no shell: paths with spaces or quotes stay intact); the exit
/// status, or 128 + signal.
int run(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ);
  if (rc != 0) throw std::runtime_error(args[0] + ": cannot run: " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error(args[0] + ": waitpid: " + std::strerror(errno));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

void write_pairs(std::ostream& out, const EvalResult& r) {
  const Association& a = r.association;
  const std::vector<double> dist = path_distances(a.gt);
  out << "# liod-eval pairs: ground truth and aligned estimate of each associated pose pair\n"
      << "# alignment=" << to_string(r.alignment.options.mode) << '\n'
      << "# gt=" << r.gt_name << '\n'
      << "# est=" << r.est_name << '\n'
      << kPairsHeader << '\n'
      << std::setprecision(10);
  for (std::size_t i = 0; i < a.gt.size(); ++i) {
    const Eigen::Vector3d& g = a.gt[i].translation();
    const Eigen::Vector3d& e = r.est_aligned[i].translation();
    const double t = a.by_time ? a.stamps[i] : std::numeric_limits<double>::quiet_NaN();
    out << t << ',' << dist[i] << ',' << g.x() << ',' << g.y() << ',' << g.z() << ',' << e.x() << ',' << e.y() << ','
        << e.z() << ',' << r.ate.translation_m[i] << ',' << r.ate.rotation_deg[i] << '\n';
  }
}

void write_pairs(const std::string& path, const EvalResult& result) {
  std::ofstream out(path);
  if (out) write_pairs(out, result);
  out.flush();
  if (!out) throw InputError(path + ": cannot write");
}

std::string default_plot_script() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the running executable (/proc/self/exe): " + ec.message());
  return (exe.parent_path() / "liod-eval-plot").string();
}

void write_plot(const std::string& png_path, const EvalResult& result, const PlotOptions& options) {
  const std::string script = options.script.empty() ? default_plot_script() : options.script;
  if (::access(script.c_str(), X_OK) != 0) {
    throw std::runtime_error(script +
                             ": the plot script is missing or not executable (it is installed beside liod-eval)");
  }
  const TempFile pairs(".csv");
  write_pairs(pairs.path(), result);
  const int status = run({script, pairs.path(), png_path, "--plane", options.plane});
  if (status != 0) throw std::runtime_error(script + " failed (exit status " + std::to_string(status) + ")");
}

}  // namespace liod::eval
