#pragma once
// Poses to a TUM trajectory file (`t x y z qx qy qz qw`), as evo and liod-eval read it.

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
  void write(const NavState& state);
  void write(double time, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
  void flush();

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, Closer> file_;
};

}  // namespace liod
