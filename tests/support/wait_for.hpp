#pragma once
// Bounded waits for tests of threads, sockets and child processes: every wait has a limit, so a
// broken test fails instead of hanging the run.
#include <chrono>
#include <thread>

namespace liod::test {

/// Polls `pred` every 5 ms until it holds or `limit` has passed; its last value.
template <typename Pred>
bool wait_for(Pred pred, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return pred();
}

}  // namespace liod::test
