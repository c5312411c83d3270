#pragma once
// Helpers shared by the daemon tests: scratch directories, the shared data folder, bounded waits.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "scratch_dir.hpp"

namespace liod::test {

inline std::filesystem::path shared_dir() { return LIOD_SHARED_DIR; }
inline std::filesystem::path binary_dir() { return LIOD_BINARY_DIR; }

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
