// Which LiDAR datagrams arrive, and in which order.
#include <algorithm>
#include <string>
#include <utility>

#include "faults.hpp"
#include "liod/fault/helios_packet_edit.hpp"

namespace liod::fault {
namespace {

bool msop_in(const Window& w, const Recording& r, const Packet& p) {
  return is_msop(p.payload) && w.contains(r.seconds_of(p.capture_time_ns));
}

std::string count(std::size_t n, std::size_t of, const std::string& what) {
  return std::to_string(n) + " of " + std::to_string(of) + " " + what;
}

}  // namespace

std::string apply(const DropPackets& f, Recording& r, Rng& rng) {
  std::vector<Packet> kept;
  kept.reserve(r.packets.size());
  std::size_t candidates = 0;
  for (Packet& p : r.packets) {
    if (msop_in(f.window, r, p)) {
      ++candidates;
      if (rng.chance(f.percent)) continue;
    }
    kept.push_back(std::move(p));
  }
  const std::size_t dropped = r.packets.size() - kept.size();
  r.packets = std::move(kept);
  return "drop: " + count(dropped, candidates, "MSOP packets lost");
}

std::string apply(const ReorderPackets& f, Recording& r, Rng& rng) {
  std::vector<std::size_t> msop;
  for (std::size_t i = 0; i < r.packets.size(); ++i) {
    if (msop_in(f.window, r, r.packets[i])) msop.push_back(i);
  }
  std::size_t delayed = 0;
  for (std::size_t i = 0; i + 1 < msop.size(); ++i) {
    if (!rng.chance(f.percent)) continue;
    const std::size_t last = std::min(msop.size() - 1, i + static_cast<std::size_t>(rng.one_to(f.max_shift)));
    // The contents move; the arrival times stay where they are (a receiver stamps in arrival order).
    for (std::size_t k = i; k < last; ++k) std::swap(r.packets[msop[k]].payload, r.packets[msop[k + 1]].payload);
    ++delayed;
  }
  return "reorder: " +
         count(delayed, msop.size(), "MSOP packets delivered after up to " + std::to_string(f.max_shift) + " later ones");
}

std::string apply(const DuplicatePackets& f, Recording& r, Rng& rng) {
  std::vector<Packet> out;
  out.reserve(r.packets.size());
  std::size_t candidates = 0;
  std::size_t copies = 0;
  for (Packet& p : r.packets) {
    bool twice = false;
    if (msop_in(f.window, r, p)) {
      ++candidates;
      twice = rng.chance(f.percent);
    }
    out.push_back(std::move(p));
    if (twice) {
      Packet copy = out.back();
      copy.capture_time_ns += 1000;  // right behind the original
      out.push_back(std::move(copy));
      ++copies;
    }
  }
  r.packets = std::move(out);
  return "duplicate: " + count(copies, candidates, "MSOP packets delivered twice");
}

std::string apply(const StopLidar& f, Recording& r, Rng&) {
  const std::size_t before = r.packets.size();
  std::vector<Packet> kept;
  kept.reserve(before);
  for (Packet& p : r.packets) {
    if (!f.window.contains(r.seconds_of(p.capture_time_ns))) kept.push_back(std::move(p));
  }
  r.packets = std::move(kept);
  return "lidar-stop: " + std::to_string(before - r.packets.size()) + " datagrams (MSOP and DIFOP) removed";
}

std::string apply(const CutStart& f, Recording& r, Rng&) {
  const std::size_t packets = r.packets.size();
  const std::size_t samples = r.imu.size();
  std::erase_if(r.packets, [&](const Packet& p) { return r.seconds_of(p.capture_time_ns) < f.at_s; });
  std::erase_if(r.imu, [&](const ImuSample& s) { return r.seconds_of_imu(s.time) < f.at_s; });
  return "cut-start: " + std::to_string(packets - r.packets.size()) + " datagrams and " +
         std::to_string(samples - r.imu.size()) + " IMU samples before " + std::to_string(f.at_s) + " s removed";
}

}  // namespace liod::fault
