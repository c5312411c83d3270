// What a vehicle meets on the road: a LiDAR that reboots, a DIFOP with another calibration, a
// pothole that clips the accelerometer, a stuck azimuth, a second sender on the LiDAR's port.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "faults.hpp"
#include "liod/drivers/rs_helios_difop.hpp"
#include "liod/fault/helios_packet_edit.hpp"

namespace liod::fault {
namespace {

/// The RS-Helios clock before any synchronisation: the real unit's header read 2017-01-06 00:00 UTC.
constexpr std::int64_t kUnsyncedEpochNs = 1'483'660'800LL * 1'000'000'000LL;

bool is_difop(const Packet& p) { return drivers::has_difop_magic(p.payload); }

}  // namespace

std::string apply(const LidarReboot& f, Recording& r, Rng&) {
  const double back_s = f.at_s + f.outage_s;
  const std::size_t before = r.packets.size();
  std::erase_if(r.packets, [&](const Packet& p) {
    const double t = r.seconds_of(p.capture_time_ns);
    return t >= f.at_s && t < back_s;
  });
  // From power-on the counters count from 0 and the clock runs from its epoch, not synchronised.
  const auto back_ns = r.origin_ns + static_cast<std::int64_t>(std::llround(back_s * 1e9));
  std::int64_t first_header_ns = -1;
  std::uint32_t counter = 0;
  std::size_t restarted = 0;
  for (Packet& p : r.packets) {
    if (p.capture_time_ns < back_ns) continue;
    if (is_difop(p)) {
      p.payload[kDifopSyncStatus] = 0;
    } else if (is_msop(p.payload)) {
      const std::int64_t header = msop_time_ns(p.payload);
      if (first_header_ns < 0) first_header_ns = header;
      set_msop_time_ns(p.payload, kUnsyncedEpochNs + (header - first_header_ns));
      set_msop_counters(p.payload, counter++);
      ++restarted;
    }
  }
  return "lidar-reboot: " + std::to_string(before - r.packets.size()) + " datagrams lost in " +
         std::to_string(f.outage_s) + " s, then " + std::to_string(restarted) +
         " MSOP packets with counters from 0 and the unsynchronised clock (2017-01-06)";
}

std::string apply(const DifopChange& f, Recording& r, Rng&) {
  int changed = 0;
  for (Packet& p : r.packets) {
    if (changed >= f.count || !is_difop(p) || r.seconds_of(p.capture_time_ns) < f.at_s) continue;
    for (std::size_t laser = 0; laser < 32; ++laser)
      set_difop_vertical_deg(p.payload, laser, difop_vertical_deg(p.payload, laser) + f.vertical_deg);
    if (f.rpm > 0) {
      p.payload[kDifopMotorRpm] = static_cast<std::uint8_t>(f.rpm >> 8);
      p.payload[kDifopMotorRpm + 1] = static_cast<std::uint8_t>(f.rpm);
    }
    ++changed;
  }
  return "difop-change: " + std::to_string(changed) + " DIFOPs with every elevation " + std::to_string(f.vertical_deg) +
         " deg higher" + (f.rpm > 0 ? " and " + std::to_string(f.rpm) + " rpm" : std::string());
}

std::string apply(const Pothole& f, Recording& r, Rng&) {
  // z(t) = h sin^2(pi t / T) has z'' = (2 pi^2 h / T^2) cos(2 pi t / T): up, down and up again,
  // back where it was with no speed left. The accelerometer reads it on top of what it read.
  const double w = 2.0 * M_PI / f.duration_s;
  std::size_t shaken = 0;
  std::size_t clipped = 0;
  for (auto& s : r.imu) {
    const double t = r.seconds_of_imu(s.time) - f.at_s;
    if (t < 0.0 || t >= f.duration_s) continue;
    ++shaken;
    s.accel.z() += f.peak_m_s2 * std::cos(w * t);
    bool clips = false;
    for (int k = 0; k < 3; ++k) {
      clips = clips || std::abs(s.accel[k]) >= f.range_m_s2;
      s.accel[k] = std::clamp(s.accel[k], -f.range_m_s2, f.range_m_s2);
    }
    clipped += clips ? 1 : 0;
  }
  return "pothole: " + std::to_string(shaken) + " IMU samples shaken (peak " + std::to_string(f.peak_m_s2) +
         " m/s^2), " + std::to_string(clipped) + " of them clipped at " + std::to_string(f.range_m_s2) + " m/s^2";
}

std::string apply(const StuckAzimuth& f, Recording& r, Rng&) {
  const auto stuck = static_cast<std::uint16_t>(std::lround(f.azimuth_deg * 100.0) % 36000);
  std::size_t packets = 0;
  for (Packet& p : r.packets) {
    if (!is_msop(p.payload) || !f.window.contains(r.seconds_of(p.capture_time_ns))) continue;
    rewrite_block_azimuths(p.payload, [&](std::uint16_t) { return stuck; });
    ++packets;
  }
  return "stuck-azimuth: every block of " + std::to_string(packets) + " MSOP packets at " +
         std::to_string(f.azimuth_deg) + " deg";
}

std::string apply(const SecondSender& f, Recording& r, Rng&) {
  const auto shift = static_cast<std::int32_t>(std::lround(f.shift_deg * 100.0));
  std::vector<Packet> out;
  out.reserve(r.packets.size() * 2);
  std::size_t sent = 0;
  for (Packet& p : r.packets) {
    const bool copy = is_msop(p.payload) && f.window.contains(r.seconds_of(p.capture_time_ns));
    out.push_back(std::move(p));
    if (!copy) continue;
    Packet foreign = out.back();
    foreign.src_ip += 1;
    foreign.capture_time_ns += 100'000;
    rewrite_block_azimuths(foreign.payload, [&](std::uint16_t az) {
      return static_cast<std::uint16_t>(((az + shift) % 36000 + 36000) % 36000);
    });
    out.push_back(std::move(foreign));
    ++sent;
  }
  r.packets = std::move(out);  // each copy right behind its original (packets are 0.67 ms apart)
  return "second-sender: " + std::to_string(sent) + " MSOP packets from another address, azimuths turned " +
         std::to_string(f.shift_deg) + " deg";
}

}  // namespace liod::fault
