#pragma once
// Bounded lock-free single-producer/single-consumer ring, the only queue between liod's threads
// (driver -> odometry, odometry -> publisher, odometry -> backend).
//
// - Never blocks: try_push() fails when the ring is full and counts the drop (live drivers must
//   not stall on a slow consumer; a lost packet is better than a late one). Replay, which must
//   be lossless to be deterministic, uses push_wait() instead, which backs off until there is room.
// - Allocation-free hand-off: push and pop *exchange* the caller's object with the slot (swap),
//   so a Scan's point buffer circulates producer -> slot -> consumer -> slot -> producer and no
//   sweep allocates once the ring has warmed up. T must be default-constructible and swappable.
// - Wake-ups go through a Notifier (an eventfd): a push costs one write() syscall, and the
//   consumer can wait on several rings at once with a bounded poll().
//
// Indices are 64-bit and never wrap in practice (2^64 pushes), so full/empty need no extra slot.
// Producer and consumer indices live on separate cache lines (64 bytes is right for x86 and the
// Cortex-A78AE of the Orin), each side caching the other's index to avoid cache-line ping-pong.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <thread>
#include <utility>

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

namespace liod::drivers {

/// A level-triggered wake-up flag any thread may raise and one thread waits on (eventfd).
class Notifier {
 public:
  Notifier() : fd_(::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
    if (fd_ < 0) throw std::runtime_error("eventfd failed");
  }
  ~Notifier() { ::close(fd_); }
  Notifier(const Notifier&) = delete;
  Notifier& operator=(const Notifier&) = delete;

  /// Wakes the waiter; never blocks (an eventfd counter only saturates after 2^64-2 posts).
  void notify() const noexcept {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(fd_, &one, sizeof one);
  }
  /// Waits until notified or `timeout` passes; clears the flag. Returns true when notified.
  bool wait(std::chrono::milliseconds timeout) const noexcept {
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(timeout.count()));
    if (r <= 0) return false;
    std::uint64_t v = 0;
    [[maybe_unused]] const auto n = ::read(fd_, &v, sizeof v);
    return true;
  }
  /// For callers that poll() this together with other descriptors (then call clear()).
  int fd() const noexcept { return fd_; }
  void clear() const noexcept {
    std::uint64_t v = 0;
    [[maybe_unused]] const auto n = ::read(fd_, &v, sizeof v);
  }

 private:
  int fd_;
};

template <typename T>
class SpscRing {
 public:
  /// `capacity` is rounded up to a power of two (index masking instead of modulo).
  explicit SpscRing(std::size_t capacity, const Notifier* consumer_wakeup = nullptr)
      : capacity_(round_up(capacity)), mask_(capacity_ - 1), slots_(new T[capacity_]), wakeup_(consumer_wakeup) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // ---- producer side -------------------------------------------------------------------
  /// Exchanges `item` with a free slot (item comes back holding a recycled object). Returns
  /// false and counts a drop when the ring is full; never blocks.
  bool try_push(T& item) noexcept {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ >= capacity_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ >= capacity_) {
        drops_.fetch_add(1, std::memory_order_relaxed);
        return false;
      }
    }
    using std::swap;
    swap(slots_[head & mask_], item);
    head_.store(head + 1, std::memory_order_release);
    if (wakeup_ != nullptr) wakeup_->notify();
    return true;
  }
  /// Lossless push for replay: backs off (sleeps 50 µs at a time) while the ring is full.
  /// Returns false only if `stop` becomes true first. The failed attempts are not drops.
  bool push_wait(T& item, const std::atomic<bool>& stop) noexcept {
    while (!stop.load(std::memory_order_relaxed)) {
      const std::uint64_t head = head_.load(std::memory_order_relaxed);
      if (head - tail_.load(std::memory_order_acquire) < capacity_) return try_push(item);
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
    return false;
  }
  /// Marks the end of the stream (after the last push); the consumer sees it once drained.
  void close() noexcept {
    closed_.store(true, std::memory_order_release);
    if (wakeup_ != nullptr) wakeup_->notify();
  }

  // ---- consumer side -------------------------------------------------------------------
  /// Exchanges `out` with the oldest item; false when empty.
  bool try_pop(T& out) noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    using std::swap;
    swap(slots_[tail & mask_], out);
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  /// The oldest item without removing it, or nullptr when empty (consumer only).
  const T* front() noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return nullptr;
    }
    return &slots_[tail & mask_];
  }
  /// True when the producer closed the stream and everything it pushed has been popped.
  bool drained() noexcept {
    // closed_ is read first: a push that happened before close() is then visible to front().
    return closed_.load(std::memory_order_acquire) && front() == nullptr;
  }
  bool closed() const noexcept { return closed_.load(std::memory_order_acquire); }

  // ---- either side (monitoring) -----------------------------------------------------------
  std::size_t capacity() const noexcept { return capacity_; }
  /// Items waiting (a snapshot; exact only when both sides are quiet).
  std::size_t size() const noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    return head >= tail ? static_cast<std::size_t>(head - tail) : 0;
  }
  std::uint64_t drops() const noexcept { return drops_.load(std::memory_order_relaxed); }
  std::uint64_t pushed() const noexcept { return head_.load(std::memory_order_relaxed); }

 private:
  static std::size_t round_up(std::size_t n) {
    if (n < 2) n = 2;
    std::size_t p = 1;
    while (p < n) p <<= 1;
    return p;
  }
  static constexpr std::size_t kLine = 64;

  const std::size_t capacity_;
  const std::size_t mask_;
  std::unique_ptr<T[]> slots_;
  const Notifier* wakeup_;
  alignas(kLine) std::atomic<std::uint64_t> head_{0};  // written by the producer
  std::uint64_t tail_cache_ = 0;                       // producer's view of tail_
  std::atomic<std::uint64_t> drops_{0};
  alignas(kLine) std::atomic<std::uint64_t> tail_{0};  // written by the consumer
  std::uint64_t head_cache_ = 0;                       // consumer's view of head_
  std::atomic<bool> closed_{false};
};

}  // namespace liod::drivers
