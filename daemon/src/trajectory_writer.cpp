#include "liod/daemon/trajectory_writer.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace liod {

TrajectoryWriter::TrajectoryWriter(const std::string& path) : path_(path), file_(std::fopen(path.c_str(), "w")) {
  if (file_ == nullptr) throw std::runtime_error(path + ": cannot open for writing: " + std::strerror(errno));
  if (std::fprintf(file_, "# t x y z qx qy qz qw (body/IMU frame in the gravity-aligned world)\n") < 0) fail(errno);
}

TrajectoryWriter::~TrajectoryWriter() { close(); }

void TrajectoryWriter::write(const NavState& s) { write(s.time, s.position, Eigen::Quaterniond(s.rotation)); }

void TrajectoryWriter::write(double time, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  if (failed() || file_ == nullptr) return;
  if (std::fprintf(file_, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", time, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(),
                   q.w()) < 0) {
    fail(errno);
  }
}

void TrajectoryWriter::flush() {
  if (!failed() && file_ != nullptr && std::fflush(file_) != 0) fail(errno);
}

bool TrajectoryWriter::close() {
  if (file_ != nullptr) {
    // A write error of buffered data shows only here (the stdio buffer reached the disk).
    flush();
    if (std::fclose(file_) != 0 && !failed()) fail(errno);
    file_ = nullptr;
  }
  return !failed();
}

void TrajectoryWriter::fail(int error_number) {
  if (failed()) return;
  error_ = path_ + ": write failed: " + std::strerror(error_number);
  spdlog::error("{}; no more poses are written to it", error_);
}

}  // namespace liod
