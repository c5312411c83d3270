#pragma once
// Runs a PoseServer's loop as the publisher thread would, for a while.
#include <poll.h>

#include <chrono>
#include <vector>

#include "liod/daemon/pose_server.hpp"

namespace liod::test {

/// Pumps the server for `ms` milliseconds.
inline void pump(PoseServer& server, int ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  std::vector<pollfd> fds;
  while (std::chrono::steady_clock::now() < deadline) {
    fds.clear();
    server.fill_pollfds(fds);
    ::poll(fds.data(), fds.size(), 5);
    server.handle(fds, 0);
    server.housekeeping();
  }
}

}  // namespace liod::test
