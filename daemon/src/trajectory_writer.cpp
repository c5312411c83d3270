#include "liod/daemon/trajectory_writer.hpp"

#include <Eigen/Geometry>
#include <stdexcept>

namespace liod {

TrajectoryWriter::TrajectoryWriter(const std::string& path) : file_(std::fopen(path.c_str(), "w")) {
  if (!file_) throw std::runtime_error(path + ": cannot open for writing");
  std::fprintf(file_.get(), "# t x y z qx qy qz qw (body/IMU frame in the gravity-aligned world)\n");
}

void TrajectoryWriter::write(const NavState& s) { write(s.time, s.position, Eigen::Quaterniond(s.rotation)); }

void TrajectoryWriter::write(double time, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  std::fprintf(file_.get(), "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", time, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(),
               q.w());
}

void TrajectoryWriter::flush() { std::fflush(file_.get()); }

}  // namespace liod
