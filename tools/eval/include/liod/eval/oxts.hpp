#pragma once
// KITTI raw's OXTS extract (DRIVE/oxts/: data/NNNNNNNNNN.txt, 30 numbers a line, and timestamps.txt)
// as a ground-truth trajectory, converted as the KITTI raw devkit's convertOxtsToPose does: the
// position by a Mercator projection whose scale is the cosine of the first fix's latitude
// (x east, y north, z the altitude), the attitude R = Rz(yaw) Ry(pitch) Rx(roll). The poses are of
// the OXTS unit's frame (KITTI's IMU frame: x forward, y left, z up), each relative to the first, so
// `liod replay --kitti-raw` poses (the IMU's, in a world levelled at the start) compare after the
// usual alignment.

#include <string>

#include "liod/eval/trajectory.hpp"

namespace liod::eval {

/// True when `path` is a KITTI raw drive folder (holding oxts/) or an oxts/ folder itself.
bool is_oxts_dir(const std::string& path);

/// The OXTS extract under `path` (a drive folder or its oxts/), stamped with timestamps.txt in
/// seconds since 1970 (the stamps carry no zone and are read as UTC, as `liod replay` reads them).
/// InputError naming the file on a missing file, a short or non-numeric line, a bad stamp.
Trajectory read_oxts(const std::string& path);

/// "YYYY-MM-DD hh:mm:ss.fffffffff" as seconds since 1970-01-01 UTC; InputError naming `where`.
double parse_kitti_stamp(const std::string& text, const std::string& where);

}  // namespace liod::eval
