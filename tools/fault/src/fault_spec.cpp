#include "liod/fault/fault_spec.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace liod::fault {
namespace {

/// The key=value pairs of one fault; every key must be consumed exactly once.
class Keys {
 public:
  Keys(std::string kind, std::string_view list) : kind_(std::move(kind)) {
    while (!list.empty()) {
      const std::size_t comma = list.find(',');
      const std::string_view item = list.substr(0, comma);
      const std::size_t eq = item.find('=');
      if (eq == std::string_view::npos || eq == 0) fail("expected key=value, got '" + std::string(item) + "'");
      if (!values_.emplace(std::string(item.substr(0, eq)), std::string(item.substr(eq + 1))).second) {
        fail("key '" + std::string(item.substr(0, eq)) + "' given twice");
      }
      list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 1);
    }
  }

  std::string text(const std::string& key, const std::string& fallback) {
    const auto it = values_.find(key);
    if (it == values_.end()) return fallback;
    std::string v = it->second;
    values_.erase(it);
    return v;
  }

  double number(const std::string& key, double fallback) {
    const auto it = values_.find(key);
    if (it == values_.end()) return fallback;
    const std::string& v = it->second;
    double out = 0.0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), out);
    if (ec != std::errc{} || end != v.data() + v.size() || !std::isfinite(out)) {
      fail("'" + key + "' = '" + v + "' is not a number");
    }
    values_.erase(it);
    return out;
  }

  double required_number(const std::string& key) {
    if (!values_.contains(key)) fail("needs '" + key + "'");
    return number(key, 0.0);
  }

  double percent(const std::string& key, double fallback) {
    const double p = number(key, fallback);
    if (p < 0.0 || p > 100.0) fail("'" + key + "' must be in [0, 100]");
    return p;
  }

  Window window() {
    Window w;
    w.from_s = number("from", w.from_s);
    w.to_s = number("to", w.to_s);
    if (!(w.from_s < w.to_s)) fail("'from' must be before 'to'");
    return w;
  }

  /// A window that must be given in full (a stop or a cut of the whole recording is no test).
  Window bounded_window() {
    if (!values_.contains("from") || !values_.contains("to")) fail("needs 'from' and 'to'");
    return window();
  }

  /// Every key consumed, else an error naming the first unknown one.
  void done() const {
    if (!values_.empty()) fail("unknown key '" + values_.begin()->first + "'");
  }

  [[noreturn]] void fail(const std::string& why) const { throw std::invalid_argument("fault '" + kind_ + "': " + why); }

 private:
  std::string kind_;
  std::map<std::string, std::string> values_;
};

Fault parse_vehicle_fault(const std::string& kind, Keys& k);

Fault parse_kind(const std::string& kind, Keys& k) {
  if (kind == "drop") return DropPackets{k.percent("percent", 10.0), k.window()};
  if (kind == "reorder") {
    ReorderPackets f{k.percent("percent", 1.0), static_cast<int>(k.number("max-shift", 3)), k.window()};
    if (f.max_shift < 1 || f.max_shift > 1000) k.fail("'max-shift' must be in [1, 1000]");
    return f;
  }
  if (kind == "duplicate") return DuplicatePackets{k.percent("percent", 1.0), k.window()};
  if (kind == "lidar-stop") return StopLidar{k.bounded_window()};
  if (kind == "imu-cut") return CutImu{k.bounded_window()};
  if (kind == "rock") {
    RockImu f;
    f.window = k.bounded_window();
    f.rate_rad_s = k.number("rate", f.rate_rad_s);
    if (!(f.rate_rad_s > 0.0 && f.rate_rad_s <= 1.0)) k.fail("'rate' must be in (0, 1] rad/s");
    return f;
  }
  if (kind == "clock-jump") {
    const std::string sensor = k.text("sensor", "lidar");
    if (sensor != "lidar" && sensor != "imu") k.fail("'sensor' must be lidar or imu");
    return ClockJump{sensor == "lidar" ? Sensor::Lidar : Sensor::Imu, k.required_number("at"), k.required_number("by")};
  }
  if (kind == "corrupt") {
    const std::string mode = k.text("mode", "garbage");
    Corruption c = Corruption::Garbage;
    if (mode == "zero") c = Corruption::ZeroRange;
    else if (mode == "max") c = Corruption::MaxRange;
    else if (mode != "garbage") k.fail("'mode' must be zero, max or garbage");
    return CorruptPoints{c, k.percent("percent", 100.0), k.window()};
  }
  if (kind == "ground-only") {
    GroundOnly f;
    f.window = k.bounded_window();
    f.max_z_m = k.number("max-z", f.max_z_m);
    f.max_range_m = k.number("max-range", f.max_range_m);
    return f;
  }
  if (kind == "cut-start") return CutStart{k.required_number("at")};
  return parse_vehicle_fault(kind, k);
}

/// The faults a vehicle meets on the road (vehicle_faults.cpp).
Fault parse_vehicle_fault(const std::string& kind, Keys& k) {
  if (kind == "lidar-reboot") {
    LidarReboot f{k.required_number("at"), k.number("outage", 30.0)};
    if (!(f.outage_s > 0.0)) k.fail("'outage' must be positive");
    return f;
  }
  if (kind == "difop-change") {
    DifopChange f{k.required_number("at"), static_cast<int>(k.number("count", 1)), k.number("vertical-deg", 0.5),
                  static_cast<int>(k.number("rpm", 0))};
    if (f.count < 1) k.fail("'count' must be at least 1");
    if (f.rpm < 0 || f.rpm > 65535) k.fail("'rpm' must be in [0, 65535]");
    return f;
  }
  if (kind == "pothole") {
    Pothole f;
    f.at_s = k.required_number("at");
    f.peak_m_s2 = k.number("peak", f.peak_m_s2);
    f.range_m_s2 = k.number("range", f.range_m_s2);
    f.duration_s = k.number("duration", f.duration_s);
    if (!(f.peak_m_s2 > 0.0 && f.range_m_s2 > 0.0 && f.duration_s > 0.0 && f.duration_s <= 1.0))
      k.fail("'peak' and 'range' must be positive, 'duration' in (0, 1] s");
    return f;
  }
  if (kind == "stuck-azimuth") {
    StuckAzimuth f{k.bounded_window(), k.number("azimuth", 100.0)};
    if (!(f.azimuth_deg >= 0.0 && f.azimuth_deg < 360.0)) k.fail("'azimuth' must be in [0, 360)");
    return f;
  }
  if (kind == "second-sender") return SecondSender{k.bounded_window(), k.number("shift-deg", 180.0)};
  throw std::invalid_argument("unknown fault '" + kind + "' (known: " + fault_syntax() + ")");
}

}  // namespace

Fault parse_fault(std::string_view text) {
  const std::size_t colon = text.find(':');
  const std::string kind(text.substr(0, colon));
  Keys keys(kind, colon == std::string_view::npos ? std::string_view{} : text.substr(colon + 1));
  Fault f = parse_kind(kind, keys);
  keys.done();
  return f;
}

std::string fault_syntax() {
  return "drop:percent=P[,from=S,to=S]; reorder:percent=P[,max-shift=N,from=S,to=S]; "
         "duplicate:percent=P[,from=S,to=S]; lidar-stop:from=S,to=S; imu-cut:from=S,to=S; rock:from=S,to=S[,rate=R]; "
         "clock-jump:sensor=lidar|imu,at=S,by=S; corrupt:mode=zero|max|garbage[,percent=P,from=S,to=S]; "
         "ground-only:from=S,to=S[,max-z=M,max-range=M]; cut-start:at=S; lidar-reboot:at=S[,outage=S]; "
         "difop-change:at=S[,count=N,vertical-deg=D,rpm=R]; pothole:at=S[,peak=A,range=A,duration=S]; "
         "stuck-azimuth:from=S,to=S[,azimuth=D]; second-sender:from=S,to=S[,shift-deg=D]";
}

}  // namespace liod::fault
