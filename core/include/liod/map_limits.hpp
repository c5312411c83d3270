#pragma once
// The local map's fixed capacities (local_map.hpp), which the configuration must respect: a voxel
// is a fixed-size slot array so that a query touches a few cache lines, and a correspondence fits
// at most this many neighbours on the stack.

namespace liod {

constexpr int kMapMaxNeighbours = 8;
constexpr int kMapMaxPointsPerVoxel = 32;

}  // namespace liod
