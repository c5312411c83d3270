#pragma once
// The graph's on-disk formats (docs/backend.md, "Persistence"), shared by the loader
// (graph_journal.cpp) and the writer (state_writer.cpp). Private to liod_backend.
//  graph.bin:   "LIODGRF1", u32 version 2, u32 0, u64 generation, u64 nodes, nodes {u64 id,
//               u32 run, pose}, u64 factors, factors {u64 from_id, u64 to_id, u8 loop, pose,
//               36 doubles information}, u64 FNV-1a of all before it.
//  journal.bin: header "LIODJRN1", u32 version 1, u32 0, u64 generation of the snapshot it
//               follows, u32 CRC-32 of those 24 bytes; then records {u32 payload length, u8 type,
//               payload, u32 CRC-32 of length, type and payload}. Payloads: node {u64 id, u32 run,
//               pose}; odometry / loop factor {as in graph.bin, without the loop byte}; pose
//               update {u64 id, pose}. A pose is 3 + 4 doubles (translation, quaternion x y z w).

#include <cstdint>
#include <string>

#include "liod/backend/map_store.hpp"

namespace liod::journal {

enum class RecordType : std::uint8_t { kNode = 1, kOdometryFactor = 2, kLoopFactor = 3, kPoseUpdate = 4 };

constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + 4;
constexpr std::size_t kFramingBytes = 4 + 1 + 4;  // length, type, CRC

/// Appends one framed record to `out`.
void append_node(std::string& out, const GraphNode& node);
void append_factor(std::string& out, const GraphFactor& factor);
void append_pose_update(std::string& out, std::uint64_t id, const Eigen::Isometry3d& pose);

/// A journal's header naming the snapshot generation it follows.
std::string header(std::uint64_t generation);
/// graph.bin's bytes for `graph` at `generation`.
std::string snapshot(const PersistedGraph& graph, std::uint64_t generation);
/// The size of snapshot() without building it.
std::uint64_t snapshot_bytes(std::size_t nodes, std::size_t factors);

}  // namespace liod::journal
