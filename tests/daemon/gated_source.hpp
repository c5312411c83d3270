#pragma once
// A LiDAR source that waits for a go signal (bounded, 30 s), so that clients connect first and
// see every pose from the first one.
#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "liod/daemon/sources.hpp"

namespace liod::test {

class GatedSource : public LidarSource {
 public:
  GatedSource(std::unique_ptr<LidarSource> inner, const std::atomic<bool>& go) : inner_(std::move(inner)), go_(go) {}
  void run(LidarOutput& out, const std::atomic<bool>& stop) override {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!go_.load() && !stop.load() && std::chrono::steady_clock::now() < deadline) {
      out.heartbeat();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    inner_->run(out, stop);
  }
  std::string describe() const override { return "gated " + inner_->describe(); }

 private:
  std::unique_ptr<LidarSource> inner_;
  const std::atomic<bool>& go_;
};

}  // namespace liod::test
