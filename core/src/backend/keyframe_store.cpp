#include "liod/backend/keyframe_store.hpp"

#include <exception>
#include <utility>

namespace liod {

KeyframeStore::KeyframeStore(std::size_t memory_keyframes, std::shared_ptr<KeyframeSpill> spill)
    : memory_keyframes_(memory_keyframes), spill_(std::move(spill)) {}

void KeyframeStore::add(BackendKeyframe keyframe) {
  Entry e;
  e.id = keyframe.id;
  e.odometry_pose = keyframe.odometry_pose;
  if (spill_) {
    // A keyframe that cannot be written (disk full, read-only) stays in memory for good: the
    // backend keeps working, only the bound is lost for it; spill_failures() reports it.
    try {
      spill_->write(keyframe);
      e.spilled = true;
    } catch (const std::exception&) {
      ++spill_failures_;
    }
  }
  times_.push_back(keyframe.time);
  e.cloud = std::make_shared<const BackendKeyframe>(std::move(keyframe));
  entries_.push_back(std::move(e));
  const std::size_t k = entries_.size() - 1;
  lru_.push_front(k);
  entries_[k].lru = lru_.begin();
  evict_over_budget();
}

std::vector<std::uint64_t> KeyframeStore::ids() const {
  std::vector<std::uint64_t> out;
  out.reserve(entries_.size());
  for (const auto& e : entries_) out.push_back(e.id);
  return out;
}

std::shared_ptr<const BackendKeyframe> KeyframeStore::get(std::size_t k) {
  Entry& e = entries_[k];
  if (e.cloud) {
    touch(k);
    return e.cloud;
  }
  e.cloud = std::make_shared<const BackendKeyframe>(spill_->read(e.id));
  ++reads_;
  lru_.push_front(k);
  e.lru = lru_.begin();
  // Keep what was just read even when everything else in memory is pinned (not spilled).
  std::shared_ptr<const BackendKeyframe> out = e.cloud;
  evict_over_budget();
  return out;
}

std::shared_ptr<const BackendKeyframe> KeyframeStore::peek(std::size_t k) const {
  const Entry& e = entries_[k];
  if (e.cloud) return e.cloud;
  return std::make_shared<const BackendKeyframe>(spill_->read(e.id));
}

void KeyframeStore::touch(std::size_t k) { lru_.splice(lru_.begin(), lru_, entries_[k].lru); }

void KeyframeStore::evict_over_budget() {
  if (memory_keyframes_ == 0 || !spill_) return;
  // From the least recently used end; keyframes that never reached the spill cannot leave.
  auto it = lru_.end();
  while (lru_.size() > memory_keyframes_ && it != lru_.begin()) {
    --it;
    Entry& e = entries_[*it];
    if (!e.spilled) continue;
    e.cloud.reset();
    it = lru_.erase(it);
    ++evictions_;
  }
}

}  // namespace liod
