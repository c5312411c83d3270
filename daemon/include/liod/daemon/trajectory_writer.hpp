#pragma once
// Poses to a TUM trajectory file (`t x y z qx qy qz qw`), as evo and liod-eval read it.
//
// A write that fails (a full disk, an I/O error) stops this writer only: it is logged once, no
// pose after it is written, and close() reports it, so that the command that asked for the file
// can exit non-zero instead of leaving a silently truncated trajectory.

#include <cstdio>
#include <memory>
#include <string>

#include <Eigen/Geometry>

#include "liod/imu_preintegration.hpp"

namespace liod {

class TrajectoryWriter {
 public:
  /// Throws std::runtime_error if the file cannot be created.
  explicit TrajectoryWriter(const std::string& path);
  ~TrajectoryWriter();
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;

  void write(const NavState& state);
  void write(double time, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
  void flush();
  /// Flushes and closes the file; false when any write failed (error() says what). Idempotent.
  bool close();

  bool failed() const noexcept { return !error_.empty(); }
  /// "path: reason" of the first failure, "" if none.
  const std::string& error() const noexcept { return error_; }

 private:
  void fail(int error_number);

  std::string path_;
  std::FILE* file_ = nullptr;
  std::string error_;
};

}  // namespace liod
