// Fuzz target: the binary point records (point_records.hpp: KITTI's velodyne .bin, the decoded
// Ouster frames) and the point-cloud path that turns them into a scan (cloud_sweep.hpp). The first
// byte picks the layout (even: x, y, z, intensity; odd: and a time), the rest is the file.
// Parsing must end with one point per whole record or an InputError naming the file; a scan made
// from them has every ring below its beam count, its points in time order, and (without a time
// field) every time within the sweep period.

#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "fuzz_support.hpp"
#include "liod/drivers/cloud_sweep.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/point_records.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  if (size == 0) return 0;
  const bool timed = (data[0] & 1U) != 0;
  const auto& layout = timed ? liod::drivers::kXyziTimeLayout : liod::drivers::kKittiVelodyneLayout;
  const std::span<const std::uint8_t> bytes(data + 1, size - 1);
  const std::string name = "0000000000.bin";
  liod::drivers::CloudSweep sweep;
  try {
    sweep.points = liod::drivers::parse_point_records(bytes, layout, name);
  } catch (const liod::drivers::InputError& e) {
    require(std::string(e.what()).find(name) != std::string::npos, "error message does not name the file");
    return 0;
  }
  require(sweep.points.size() * layout.fields * 4 == bytes.size(), "not one point per record");
  sweep.has_time = timed;
  liod::drivers::CloudScanConfig config;
  config.beam_elevations_deg = {-24.0, -8.5, -2.0, 2.0};
  liod::drivers::CloudScanStats stats;
  const liod::Scan scan = liod::drivers::make_scan(sweep, config, &stats);
  require(scan.points.size() + stats.no_beam + stats.too_near == sweep.points.size(), "points lost uncounted");
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const auto& p = scan.points[i];
    require(p.ring < scan.beam_count, "ring beyond the beam count");
    require(std::isfinite(p.time) && p.time >= 0.0F, "a point time that is not a time after the start");
    if (!timed) require(p.time <= static_cast<float>(config.sweep_period_s), "azimuth time beyond the sweep");
    if (i > 0) require(scan.points[i - 1].time <= p.time, "points not in time order");
  }
  return 0;
}
