#include "liod/eval/io.hpp"

#include <Eigen/SVD>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace liod::eval {
namespace {

[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& what) {
  throw InputError(name + ":" + std::to_string(line) + ": " + what);
}

std::ifstream open(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open file");
  return in;
}

/// Splits a line into numbers; returns false on a token that is not a finite number.
/// `bad` receives the offending token. Comments ('#') end the line.
bool parse_numbers(const std::string& line, std::vector<double>& out, std::string& bad) {
  out.clear();
  std::size_t i = 0;
  const std::size_t end = line.find('#') == std::string::npos ? line.size() : line.find('#');
  while (i < end) {
    while (i < end && std::isspace(static_cast<unsigned char>(line[i])) != 0) ++i;
    if (i >= end) break;
    std::size_t j = i;
    while (j < end && std::isspace(static_cast<unsigned char>(line[j])) == 0) ++j;
    const char* first = line.data() + i;
    const char* last = line.data() + j;
    // from_chars rejects a leading '+', which some writers emit.
    if (*first == '+' && last - first > 1) ++first;
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last || !std::isfinite(value)) {
      bad = line.substr(i, j - i);
      return false;
    }
    out.push_back(value);
    i = j;
  }
  return true;
}

std::string expect_message(std::size_t want, const char* layout, std::size_t got) {
  return "expected " + std::to_string(want) + " numbers (" + layout + "), got " + std::to_string(got);
}

/// Nearest rotation in the Frobenius sense (SVD), refusing matrices that are no rotation at all.
Eigen::Matrix3d project_to_so3(const Eigen::Matrix3d& M, const std::string& name, std::size_t line) {
  const double off = (M.transpose() * M - Eigen::Matrix3d::Identity()).norm();
  if (off > 1e-2 || M.determinant() <= 0.0) {
    fail(name, line, "rotation part is not a rotation matrix (|R^T R - I| = " + std::to_string(off) +
                         ", det = " + std::to_string(M.determinant()) + ")");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace

Format parse_format(const std::string& text) {
  if (text == "auto") return Format::Auto;
  if (text == "tum") return Format::Tum;
  if (text == "kitti") return Format::Kitti;
  throw InputError("unknown trajectory format '" + text + "' (want auto, tum or kitti)");
}

const char* to_string(Format format) {
  switch (format) {
    case Format::Tum: return "tum";
    case Format::Kitti: return "kitti";
    case Format::Auto: break;
  }
  return "auto";
}

// Calls row(values, line number) for every non-empty line of `columns` numbers; anything else is
// an error naming the file and line.
template <typename Row>
void for_each_row(std::istream& in, const std::string& name, std::size_t columns, const char* layout, Row row) {
  std::string line;
  std::vector<double> v;
  std::string bad;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!parse_numbers(line, v, bad)) fail(name, line_no, "not a number: '" + bad + "'");
    if (v.empty()) continue;
    if (v.size() != columns) fail(name, line_no, expect_message(columns, layout, v.size()));
    row(v, line_no);
  }
}

Trajectory read_tum(std::istream& in, const std::string& name) {
  Trajectory traj;
  traj.name = name;
  for_each_row(in, name, 8, "t x y z qx qy qz qw", [&](const std::vector<double>& v, std::size_t line_no) {
    if (!traj.stamps.empty() && v[0] <= traj.stamps.back()) {
      std::ostringstream msg;
      msg << std::setprecision(17) << "timestamp " << v[0] << " does not increase (previous " << traj.stamps.back()
          << ")";
      fail(name, line_no, msg.str());
    }
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // Eigen's constructor order is (w, x, y, z)
    const double n = q.norm();
    // Files round quaternions to a few digits; anything far from unit length is a wrong column order.
    if (std::abs(n - 1.0) > 1e-2) fail(name, line_no, "quaternion norm " + std::to_string(n) + " is not 1");
    q.normalize();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = q.toRotationMatrix();
    pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    traj.stamps.push_back(v[0]);
    traj.poses.push_back(pose);
  });
  if (traj.poses.empty()) throw InputError(name + ": no poses (empty file or only comments)");
  return traj;
}

Trajectory read_kitti(std::istream& in, const std::string& name) {
  Trajectory traj;
  traj.name = name;
  for_each_row(in, name, 12, "r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz", [&](const std::vector<double>& v,
                                                                                 std::size_t line_no) {
    Eigen::Matrix3d R;
    R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = project_to_so3(R, name, line_no);
    pose.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
    traj.poses.push_back(pose);
  });
  if (traj.poses.empty()) throw InputError(name + ": no poses (empty file or only comments)");
  return traj;
}

std::vector<double> read_times(std::istream& in, const std::string& name) {
  std::vector<double> stamps;
  for_each_row(in, name, 1, "t", [&](const std::vector<double>& v, std::size_t line_no) {
    if (!stamps.empty() && v[0] <= stamps.back()) fail(name, line_no, "timestamp does not increase");
    stamps.push_back(v[0]);
  });
  if (stamps.empty()) throw InputError(name + ": no timestamps");
  return stamps;
}

Trajectory read_tum(const std::string& path) {
  auto in = open(path);
  return read_tum(in, path);
}

Trajectory read_kitti(const std::string& path) {
  auto in = open(path);
  return read_kitti(in, path);
}

std::vector<double> read_times(const std::string& path) {
  auto in = open(path);
  return read_times(in, path);
}

Format detect_format(const std::string& path) {
  auto in = open(path);
  std::string line;
  std::vector<double> v;
  std::string bad;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!parse_numbers(line, v, bad)) fail(path, line_no, "not a number: '" + bad + "'");
    if (v.empty()) continue;
    if (v.size() == 8) return Format::Tum;
    if (v.size() == 12) return Format::Kitti;
    fail(path, line_no, "cannot tell the format: " + std::to_string(v.size()) +
                            " numbers (TUM has 8, KITTI 12); pass --format");
  }
  throw InputError(path + ": no poses (empty file or only comments)");
}

Trajectory read_trajectory(const std::string& path, Format format) {
  if (format == Format::Auto) format = detect_format(path);
  return format == Format::Tum ? read_tum(path) : read_kitti(path);
}

void write_tum(std::ostream& out, const Trajectory& trajectory) {
  out << std::setprecision(17);
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Quaterniond q(trajectory.poses[i].linear());
    const Eigen::Vector3d& p = trajectory.poses[i].translation();
    const double t = trajectory.has_stamps() ? trajectory.stamps[i] : static_cast<double>(i);
    out << t << ' ' << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
        << q.w() << '\n';
  }
}

void write_kitti(std::ostream& out, const Trajectory& trajectory) {
  out << std::setprecision(17);
  for (const auto& pose : trajectory.poses) {
    const Eigen::Matrix<double, 3, 4> m = pose.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) out << m(r, c) << ((r == 2 && c == 3) ? '\n' : ' ');
    }
  }
}

}  // namespace liod::eval
