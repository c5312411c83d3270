#pragma once
// The backend's keyframes over a long drive, in bounded memory (issues 5 and 7). Every keyframe's
// pose and time stay in memory (the graph and the loop-candidate search need all of them), but
// only a bounded number of clouds do: the loop check needs the current keyframe and a candidate's
// sub-map, the global map needs each cloud once at the end. The clouds of all keyframes are
// handed to a KeyframeSpill as they arrive (write-through: a keyframe is written once, and
// evicting it later costs nothing) and the store keeps the most recently used ones, new
// keyframes included, in an LRU cache; the others are read back on demand. Pure: the spill is an
// interface, its file implementation (KeyframeDirectory) lives in map_store.cpp, among the units of
// the backend that do I/O. Without a spill every cloud stays in memory.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <list>
#include <memory>
#include <vector>

namespace liod {

/// The backend's copy of a keyframe: points in its own body frame (so that a pose-graph update
/// moves them for free), stored as floats at the backend's resolution.
struct BackendKeyframe {
  std::uint64_t id = 0;
  double time = 0.0;
  Eigen::Isometry3d odometry_pose = Eigen::Isometry3d::Identity();  // T_odom_body from the front end
  std::vector<Eigen::Vector3f> planes;      // body frame, map density
  std::vector<Eigen::Vector3f> edges;
  std::vector<Eigen::Vector3f> similarity;  // the front end's Hausdorff cloud (sparse)
};

/// Where keyframes go when they leave memory.
class KeyframeSpill {
 public:
  virtual ~KeyframeSpill() = default;
  /// Stores a keyframe for later reads; throws when it cannot (the store then keeps it in memory).
  virtual void write(const BackendKeyframe& keyframe) = 0;
  /// Reads back a keyframe written before, bit for bit; throws when it cannot.
  virtual BackendKeyframe read(std::uint64_t id) const = 0;
};

class KeyframeStore {
 public:
  /// `memory_keyframes`: clouds kept in memory (0 = all); `spill`: where every keyframe is
  /// written (nullptr = none, then all clouds stay in memory).
  KeyframeStore(std::size_t memory_keyframes, std::shared_ptr<KeyframeSpill> spill);

  void add(BackendKeyframe keyframe);
  std::size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  std::uint64_t id(std::size_t k) const { return entries_[k].id; }
  double time(std::size_t k) const { return times_[k]; }
  const Eigen::Isometry3d& odometry_pose(std::size_t k) const { return entries_[k].odometry_pose; }
  /// Every keyframe's time, in the order added.
  const std::vector<double>& times() const { return times_; }
  std::vector<std::uint64_t> ids() const;

  /// Keyframe k with its clouds: from memory, else read from the spill and cached (the least
  /// recently used cloud leaves memory). The pointer stays valid after an eviction.
  std::shared_ptr<const BackendKeyframe> get(std::size_t k);
  /// The same without touching the cache (a sweep over all keyframes, e.g. the global map,
  /// must not flush the loop check's working set).
  std::shared_ptr<const BackendKeyframe> peek(std::size_t k) const;

  bool in_memory(std::size_t k) const { return entries_[k].cloud != nullptr; }
  /// Whether keyframe k reached the spill (false: no spill, or its write failed).
  bool spilled(std::size_t k) const { return entries_[k].spilled; }
  std::size_t in_memory_count() const { return lru_.size(); }
  std::size_t reads() const { return reads_; }          // clouds read back from the spill
  std::size_t evictions() const { return evictions_; }
  std::size_t spill_failures() const { return spill_failures_; }

 private:
  struct Entry {
    std::uint64_t id = 0;
    Eigen::Isometry3d odometry_pose = Eigen::Isometry3d::Identity();
    std::shared_ptr<const BackendKeyframe> cloud;  // null when only in the spill
    bool spilled = false;
    std::list<std::size_t>::iterator lru;          // position in lru_ when in memory
  };
  void touch(std::size_t k);
  void evict_over_budget();

  std::size_t memory_keyframes_;
  std::shared_ptr<KeyframeSpill> spill_;
  std::vector<Entry> entries_;
  std::vector<double> times_;
  std::list<std::size_t> lru_;  // in-memory keyframes, most recently used first
  std::size_t reads_ = 0;
  std::size_t evictions_ = 0;
  std::size_t spill_failures_ = 0;
};

}  // namespace liod
