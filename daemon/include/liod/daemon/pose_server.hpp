#pragma once
// The pose socket's server side: a Unix stream socket serving any number of clients, driven by
// the publisher thread. Every write is non-blocking; each client has a bounded output buffer.
// A client that falls behind skips whole messages (counted) instead of slowing anyone down, and
// one that accepts nothing for pose_socket.stuck_timeout_s while data waits is disconnected.

#include <poll.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "liod/config.hpp"
#include "liod/daemon/pose_protocol.hpp"

namespace liod {

struct PoseServerStats {
  std::uint64_t clients = 0;           ///< connected now
  std::uint64_t accepted = 0;
  std::uint64_t rejected = 0;          ///< over max_clients
  std::uint64_t dropped_stuck = 0;     ///< disconnected for not reading
  std::uint64_t skipped_messages = 0;  ///< messages not queued to a client whose buffer was full
  std::uint64_t sent_messages = 0;     ///< messages queued (per client)
};

class PoseServer {
 public:
  /// Creates the socket file at `path` (a stale file is replaced; the directory must exist) with
  /// the given octal permission bits. Throws std::runtime_error on failure.
  PoseServer(const std::string& path, const PoseSocketConfig& config);
  ~PoseServer();
  PoseServer(const PoseServer&) = delete;
  PoseServer& operator=(const PoseServer&) = delete;

  /// Appends the descriptors to poll (listener + clients, POLLOUT where data waits).
  void fill_pollfds(std::vector<pollfd>& fds) const;
  /// Handles the poll results for the descriptors fill_pollfds added (starting at `first`).
  void handle(const std::vector<pollfd>& fds, std::size_t first);
  /// Queues a pose to every client (that wants its rate) and tries to send at once.
  void broadcast(const pose::PoseMessage& m);
  void broadcast_health(const std::string& json);
  /// Disconnects stuck clients; call at least a few times per second.
  void housekeeping();

  const PoseServerStats& stats() const { return stats_; }
  const std::string& path() const { return path_; }

 private:
  struct Client {
    int fd = -1;
    pose::ClientMode mode;
    pose::RequestReader requests;
    std::vector<std::uint8_t> out;  // bytes queued, whole messages only
    std::size_t sent = 0;           // bytes of `out` already written
    std::chrono::steady_clock::time_point last_progress;
  };
  void accept_clients();
  void read_requests(Client& c);
  void flush(Client& c);
  void close_client(std::size_t i);
  void queue(Client& c, const std::uint8_t* data, std::size_t n);

  std::string path_;
  PoseSocketConfig config_;
  int listen_fd_ = -1;
  std::vector<Client> clients_;
  PoseServerStats stats_;
  std::uint32_t sequence_ = 0;
  std::vector<std::uint8_t> binary_;
};

}  // namespace liod
