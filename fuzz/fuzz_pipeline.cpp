// Fuzz target: bytes to a published pose. RS-Helios payloads and IMU samples, interleaved on one
// clock, through the decoder (sweep assembly) and the odometry as the daemon's odometry thread
// runs it (a scan is processed once the IMU has reached its end), each result gated as the
// daemon gates it before it goes out `ok` (the odometry's status, state_sanity.hpp).
//
// Input: byte 0 bit 0: RS-Helios-16P (else 5515). Then records, each a tag byte and a time step:
//   tag % 4 == 0   IMU: step byte (0.5 ms units, +1), then 6 int16 little-endian: gyro x, y, z
//                  (1e-3 rad/s), accelerometer x, y, z (4e-3 m/s^2); 14 bytes in all
//   otherwise      a payload: step byte, then up to 1248 bytes (an MSOP or DIFOP packet)
// The scans are timed on the arrival clock (the host clock of time.lidar_clock: auto).
// Checked: every pose published ok is finite, and moved from the previous ok pose no faster than
// the plausible speed allows (a wild pose would).

#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>

#include "fuzz_support.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/lidar_inertial_odometry.hpp"
#include "liod/state_sanity.hpp"

namespace {

using namespace liod;
using namespace liod::drivers;

constexpr std::size_t kImuRecord = 14;
// What the daemon publishes without `ok` (pipeline.cpp status_flags).
constexpr std::uint32_t kNotOk = kStatusInitializing | kStatusDegenerate | kStatusImuGap | kStatusFewFeatures |
                                 kStatusSpeedUnknown | kStatusImuInconsistent;
// Slack on the speed bound between ok poses: a registration may move a pose by a correspondence
// gate or so beyond what the velocity carried it.
constexpr double kJumpSlackM = 2.0;

AngleTable spread_angles(HeliosModel model) {
  AngleTable t;
  for (std::size_t i = 0; i < beam_count(model); ++i) {
    t.vertical_deg.push_back(-25.0 + 40.0 * static_cast<double>(i) / static_cast<double>(beam_count(model)));
    t.horizontal_deg.push_back(0.0);
  }
  return t;
}

std::int16_t le16(const std::uint8_t* p) { return static_cast<std::int16_t>(p[0] | (p[1] << 8)); }

struct Publisher {
  StateLimits limits;
  std::optional<NavState> last_ok;

  void publish(const OdometryResult& r) {
    if ((r.status & kNotOk) != 0) return;
    if (check_state(r.state, limits) != StateFault::kNone || check_covariance(r.covariance) != StateFault::kNone) return;
    fuzz::require(r.state.position.allFinite() && r.state.rotation.allFinite(), "ok pose not finite");
    if (last_ok) {
      const double dt = r.state.time - last_ok->time;
      fuzz::require(dt > 0.0, "ok pose not after the previous ok pose");
      const double moved = (r.state.position - last_ok->position).norm();
      fuzz::require(moved <= limits.max_speed_mps * dt + kJumpSlackM, "ok pose jumped beyond the plausible speed");
    }
    last_ok = r.state;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  HeliosOptions options;
  options.model = (data[0] & 1U) != 0 ? HeliosModel::Helios16P : HeliosModel::Helios5515;
  options.angles = spread_angles(options.model);
  options.use_difop_angles = false;
  options.msop.time_source = TimeSource::ArrivalTime;

  FrontEndConfig config;
  LidarInertialOdometry odometry(config);
  Publisher publisher;
  std::deque<Scan> pending;
  RsHeliosDecoder decoder(options, [&](Scan& scan, const SweepInfo& info) {
    if (!info.truncated && pending.size() < 4) pending.push_back(std::move(scan));
  });
  auto process_ready = [&](bool all) {
    while (!pending.empty() && (all || odometry.latest_imu_time() >= odometry.scan_end_time(pending.front()))) {
      if (const auto result = odometry.process(pending.front())) publisher.publish(*result);
      pending.pop_front();
    }
  };

  std::int64_t clock_ns = 1'700'000'000'000'000'000;
  std::span<const std::uint8_t> in(data + 1, size - 1);
  while (in.size() >= 2) {
    const std::uint8_t tag = in[0];
    clock_ns += (static_cast<std::int64_t>(in[1]) + 1) * 500'000;
    in = in.subspan(2);
    if (tag % 4 == 0) {
      if (in.size() < kImuRecord - 2) break;
      ImuSample s;
      s.time = static_cast<double>(clock_ns) * 1e-9;
      for (int i = 0; i < 3; ++i) {
        s.gyro[i] = le16(in.data() + 2 * i) * 1e-3;
        s.accel[i] = le16(in.data() + 6 + 2 * i) * 4e-3;
      }
      in = in.subspan(kImuRecord - 2);
      odometry.add_imu(s);
      process_ready(false);
    } else {
      const std::size_t n = std::min(in.size(), helios::kPacketBytes);
      decoder.feed(in.first(n), clock_ns);
      in = in.subspan(n);
    }
  }
  decoder.flush();
  process_ready(true);
  return 0;
}
