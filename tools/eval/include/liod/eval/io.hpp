#pragma once
// Trajectory files: TUM (`t x y z qx qy qz qw`) and KITTI (12 numbers a line, row-major [R|t]),
// read as evo and the KITTI devkit read them, but strict: a line that does not parse is an error that
// names the file and the line, never silently skipped (the devkit drops such lines, which shifts every
// later index and corrupts the pairing without a word).

#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

/// Bad input: a message for the user, already naming file and line.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Format { Auto, Tum, Kitti };

Format parse_format(const std::string& text);  // "auto" | "tum" | "kitti"; throws InputError
const char* to_string(Format format);

/// TUM: '#' starts a comment, blank lines are ignored, stamps must increase strictly.
Trajectory read_tum(std::istream& in, const std::string& name);
Trajectory read_tum(const std::string& path);

/// KITTI: no stamps. Rotations are projected onto SO(3) (files carry ~6 digits).
Trajectory read_kitti(std::istream& in, const std::string& name);
Trajectory read_kitti(const std::string& path);

/// KITTI's times.txt: one stamp (s) a line.
std::vector<double> read_times(std::istream& in, const std::string& name);
std::vector<double> read_times(const std::string& path);

/// Auto picks by the first data line: 8 numbers = TUM, 12 = KITTI.
Format detect_format(const std::string& path);
Trajectory read_trajectory(const std::string& path, Format format);

void write_tum(std::ostream& out, const Trajectory& trajectory);
void write_kitti(std::ostream& out, const Trajectory& trajectory);

}  // namespace liod::eval
