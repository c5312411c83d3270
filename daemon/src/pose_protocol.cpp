#include "liod/daemon/pose_protocol.hpp"

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>

namespace liod::pose {
namespace {

void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}
void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put_f64(std::vector<std::uint8_t>& out, double d) {
  const auto v = std::bit_cast<std::uint64_t>(d);
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
std::uint16_t get_u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t get_u32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[3]} << 24);
}
double get_f64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return std::bit_cast<double>(v);
}

void put_header(std::vector<std::uint8_t>& out, MessageType type, std::uint32_t length, std::uint32_t seq) {
  out.insert(out.end(), std::begin(kMagic), std::end(kMagic));
  put_u16(out, kVersion);
  put_u16(out, static_cast<std::uint16_t>(type));
  put_u32(out, length);
  put_u32(out, seq);
}

void json_array(std::string& s, const double* v, int n) {
  char buf[40];
  s += '[';
  for (int i = 0; i < n; ++i) {
    // %.17g round-trips a double exactly; JSON has no NaN/inf, so those become null.
    if (std::isfinite(v[i])) {
      std::snprintf(buf, sizeof buf, "%.17g", v[i]);
      s += buf;
    } else {
      s += "null";
    }
    if (i + 1 < n) s += ',';
  }
  s += ']';
}

void apply_request(std::string_view req, ClientMode& mode) {
  while (!req.empty() && (req.back() == '\r' || req.back() == ' ')) req.remove_suffix(1);
  if (req == "json") mode.json = true;
  else if (req == "binary") mode.json = false;
  else if (req == "scan") mode.scan_only = true;
  else if (req == "all") mode.scan_only = false;
}

}  // namespace

void encode(const PoseMessage& m, std::vector<std::uint8_t>& out) {
  put_header(out, m.type, static_cast<std::uint32_t>(kPoseMessageSize), m.sequence);
  put_f64(out, m.time);
  for (int i = 0; i < 3; ++i) put_f64(out, m.position[i]);
  put_f64(out, m.orientation.x());
  put_f64(out, m.orientation.y());
  put_f64(out, m.orientation.z());
  put_f64(out, m.orientation.w());
  for (int i = 0; i < 3; ++i) put_f64(out, m.velocity[i]);
  for (int i = 0; i < 3; ++i) put_f64(out, m.angular_rate[i]);
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) put_f64(out, m.covariance(r, c));
  }
  put_u32(out, m.flags);
  put_u32(out, m.correction_sequence);
  for (int i = 0; i < 3; ++i) put_f64(out, m.map_position[i]);
  put_f64(out, m.map_orientation.x());
  put_f64(out, m.map_orientation.y());
  put_f64(out, m.map_orientation.z());
  put_f64(out, m.map_orientation.w());
}

void encode_health(const std::string& json, std::uint32_t sequence, std::vector<std::uint8_t>& out) {
  put_header(out, MessageType::Health, static_cast<std::uint32_t>(kHeaderSize + json.size()), sequence);
  out.insert(out.end(), json.begin(), json.end());
}

std::string flag_names(std::uint32_t flags) {
  static const char* kNames[] = {"initializing", "ok",           "degenerate", "imu_lost",        "lidar_lost",
                                 "keyframe",     "few_features", "clock_jump", "imu_inconsistent", "implausible",
                                 "sweep_truncated", "calibration_changed", "imu_saturated", "stale",
                                 "not_localized", "extrinsics_suspect"};
  std::string s;
  for (int i = 0; i < static_cast<int>(std::size(kNames)); ++i) {
    if ((flags & (1U << i)) == 0 || *kNames[i] == '\0') continue;
    if (!s.empty()) s += '|';
    s += kNames[i];
  }
  return s.empty() ? "none" : s;
}

std::string to_json_line(const PoseMessage& m) {
  std::string s;
  s.reserve(900);
  s += m.type == MessageType::ScanPose ? "{\"type\":\"scan\"" : "{\"type\":\"imu\"";
  s += ",\"seq\":" + std::to_string(m.sequence);
  s += ",\"t\":";
  if (std::isfinite(m.time)) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.9f", m.time);
    s += buf;
  } else {
    s += "null";  // JSON has no NaN (an implausible pose may carry one)
  }
  s += ",\"p\":";
  json_array(s, m.position.data(), 3);
  const double q[4] = {m.orientation.x(), m.orientation.y(), m.orientation.z(), m.orientation.w()};
  s += ",\"q\":";
  json_array(s, q, 4);
  s += ",\"v\":";
  json_array(s, m.velocity.data(), 3);
  s += ",\"w\":";
  json_array(s, m.angular_rate.data(), 3);
  double cov[21];
  int k = 0;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) cov[k++] = m.covariance(r, c);
  }
  s += ",\"cov\":";
  json_array(s, cov, 21);
  s += ",\"flags\":" + std::to_string(m.flags) + ",\"status\":\"" + flag_names(m.flags) + "\"";
  s += ",\"map_seq\":" + std::to_string(m.correction_sequence) + ",\"map_p\":";
  json_array(s, m.map_position.data(), 3);
  const double mq[4] = {m.map_orientation.x(), m.map_orientation.y(), m.map_orientation.z(), m.map_orientation.w()};
  s += ",\"map_q\":";
  json_array(s, mq, 4);
  s += "}\n";
  return s;
}

DecodeStatus decode(std::span<const std::uint8_t> b, Message& out, std::size_t& consumed) {
  consumed = 0;
  if (b.size() < kHeaderSize) {
    // A wrong magic is reported as soon as its bytes are there.
    for (std::size_t i = 0; i < b.size() && i < 4; ++i) {
      if (b[i] != kMagic[i]) return DecodeStatus::Invalid;
    }
    return DecodeStatus::NeedMore;
  }
  if (std::memcmp(b.data(), kMagic, 4) != 0 || get_u16(b.data() + 4) != kVersion) return DecodeStatus::Invalid;
  const auto type = get_u16(b.data() + 6);
  const std::uint32_t length = get_u32(b.data() + 8);
  const bool pose = type == 1 || type == 2;
  if ((pose && length != kPoseMessageSize) || (type == 3 && (length < kHeaderSize || length > kMaxMessageSize)) ||
      (!pose && type != 3)) {
    return DecodeStatus::Invalid;
  }
  if (b.size() < length) return DecodeStatus::NeedMore;
  out.type = static_cast<MessageType>(type);
  const std::uint8_t* p = b.data();
  if (pose) {
    PoseMessage& m = out.pose;
    m.type = out.type;
    m.sequence = get_u32(p + 12);
    m.time = get_f64(p + 16);
    for (int i = 0; i < 3; ++i) m.position[i] = get_f64(p + 24 + 8 * i);
    m.orientation = Eigen::Quaterniond(get_f64(p + 72), get_f64(p + 48), get_f64(p + 56), get_f64(p + 64));
    for (int i = 0; i < 3; ++i) m.velocity[i] = get_f64(p + 80 + 8 * i);
    for (int i = 0; i < 3; ++i) m.angular_rate[i] = get_f64(p + 104 + 8 * i);
    int k = 0;
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) {
        m.covariance(r, c) = m.covariance(c, r) = get_f64(p + 128 + 8 * k);
        ++k;
      }
    }
    m.flags = get_u32(p + 296);
    m.correction_sequence = get_u32(p + 300);
    for (int i = 0; i < 3; ++i) m.map_position[i] = get_f64(p + 304 + 8 * i);
    m.map_orientation = Eigen::Quaterniond(get_f64(p + 352), get_f64(p + 328), get_f64(p + 336), get_f64(p + 344));
  } else {
    out.health.assign(reinterpret_cast<const char*>(p + kHeaderSize), length - kHeaderSize);
  }
  consumed = length;
  return DecodeStatus::Ok;
}

void RequestReader::feed(std::string_view bytes, ClientMode& mode) {
  while (!bytes.empty()) {
    const std::size_t nl = bytes.find('\n');
    if (!overlong_) {
      line_.append(bytes.substr(0, nl));
      if (line_.size() > kMaxLine) {  // not a request: skip to its end rather than grow, and never
        line_.clear();                // take its tail for one (that would depend on the chunking)
        overlong_ = true;
      }
    }
    if (nl == std::string_view::npos) return;
    if (!overlong_) apply_request(line_, mode);
    line_.clear();
    overlong_ = false;
    bytes.remove_prefix(nl + 1);
  }
}

Eigen::Matrix<double, 6, 6> pose_covariance_from_state(const Eigen::Ref<const Eigen::MatrixXd>& s) {
  // Filter order: [rotation 0..2, position 3..5, ...]; the message order is [position, rotation].
  Eigen::Matrix<double, 6, 6> c;
  c.block<3, 3>(0, 0) = s.block<3, 3>(3, 3);
  c.block<3, 3>(0, 3) = s.block<3, 3>(3, 0);
  c.block<3, 3>(3, 0) = s.block<3, 3>(0, 3);
  c.block<3, 3>(3, 3) = s.block<3, 3>(0, 0);
  return c;
}

}  // namespace liod::pose
