#pragma once
// The pose socket's wire format, version 2 (docs/pose-protocol.md is the reference for clients
// written in other languages). Every multi-byte field is LITTLE-endian, written byte by byte so
// the host's byte order never matters; doubles are IEEE-754 binary64.
//
//   offset size  field
//   0      4     magic "LIOD" (bytes 4C 49 4F 44)
//   4      2     version (1)
//   6      2     type: 1 scan-rate pose, 2 IMU-rate pose, 3 health (JSON body)
//   8      4     length of the whole message in bytes (360 for poses, 16 + n for health)
//   12     4     sequence number (per connection stream of the server, +1 per message sent)
//   -- pose body (types 1, 2) --
//   16     8     time, s (the IMU clock, Unix epoch when the sensors are synchronised)
//   24     24    position x y z, m, odometry frame (gravity-aligned, z up, origin at the first
//                pose; continuous: never jumps, drifts slowly; REP 105's odom)
//   48     32    orientation quaternion qx qy qz qw (body -> odometry frame)
//   80     24    velocity x y z, m/s, odometry frame
//   104    24    angular rate x y z, rad/s, body frame (gyro minus estimated bias)
//   128    168   pose covariance: upper triangle (row-major, 21 values) of the 6x6 covariance of
//                [position x y z (m), rotation error x y z (rad, body frame, R = R_est * Exp(e))]
//   296    4     status flags (Flag below)
//   300    4     map correction sequence: +1 each time the backend's correction changes (a loop
//                closed); 0 while there is none
//   304    24    position x y z, m, map frame (REP 105's map: the odometry pose with the backend's
//                latest correction T_map_odom applied; jumps when a loop closes)
//   328    32    orientation quaternion qx qy qz qw (body -> map frame)
//   -- health body (type 3) --
//   16     n     UTF-8 JSON object
//
// A client that wants text sends the line "json\n" after connecting: from then on it receives one
// JSON object per line. "binary\n" switches back; "scan\n" selects scan-rate poses only and
// "all\n" both rates (the default).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace liod::pose {

inline constexpr std::uint8_t kMagic[4] = {'L', 'I', 'O', 'D'};
inline constexpr std::uint16_t kVersion = 2;
inline constexpr std::size_t kHeaderSize = 16;
inline constexpr std::size_t kPoseMessageSize = 360;
inline constexpr std::size_t kMaxMessageSize = 1 << 20;

enum class MessageType : std::uint16_t { ScanPose = 1, ImuPose = 2, Health = 3 };

enum Flag : std::uint32_t {
  kInitializing = 1U << 0,  ///< the filter has just started (first pose, or after a reset)
  kOk = 1U << 1,            ///< initialised, well constrained, both sensors alive
  kDegenerate = 1U << 2,    ///< the scan constrained the translation poorly (tunnel, open field)
  kImuLost = 1U << 3,       ///< IMU data missing or late
  kLidarLost = 1U << 4,     ///< no LiDAR sweep for longer than drivers.lidar.lost_after_s
  kKeyframe = 1U << 5,      ///< this scan became a keyframe
  kFewFeatures = 1U << 6,   ///< too few features for a reliable update
  kClockJump = 1U << 7,     ///< a clock stepped within time.jump_flag_s, or the LiDAR's clock jumped in this scan or disagrees with the host
  kImuInconsistent = 1U << 8,  ///< the scan's registration contradicted the IMU prediction far beyond its covariance
  kImplausible = 1U << 9,   ///< the state failed the publishing gate (state_gate.hpp): not finite, too fast, absurd bias or covariance
  kSweepTruncated = 1U << 10,  ///< sweeps before this scan were cut at the size cap and dropped (a stuck azimuth)
  kCalibrationChanged = 1U << 11,  ///< the LiDAR's DIFOP disagreed with the calibration in use, or a new one began
  kImuSaturated = 1U << 12,    ///< an IMU sample since the previous pose clipped at the sensor's range
  kStale = 1U << 13,           ///< published more than pose_socket.stale_after_s after its input arrived (live)
  kNotLocalized = 1U << 14,    ///< the map-frame pose is the odometry's: no backend, or not yet placed in the saved map
  kExtrinsicsSuspect = 1U << 15,  ///< the start-up check found the configured LiDAR-IMU extrinsic or time offset off (extrinsics_check.hpp)
};

struct PoseMessage {
  MessageType type = MessageType::ScanPose;
  std::uint32_t sequence = 0;
  double time = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  std::uint32_t flags = 0;
  std::uint32_t correction_sequence = 0;
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond map_orientation = Eigen::Quaterniond::Identity();
};

/// Appends the 360-byte binary form of `m` to `out`.
void encode(const PoseMessage& m, std::vector<std::uint8_t>& out);
/// Appends a health message (header + JSON body).
void encode_health(const std::string& json, std::uint32_t sequence, std::vector<std::uint8_t>& out);
/// One JSON line (with '\n') for the text mode.
std::string to_json_line(const PoseMessage& m);
/// "ok|keyframe" style names of the set flags.
std::string flag_names(std::uint32_t flags);

/// A decoded message of any type.
struct Message {
  MessageType type = MessageType::ScanPose;
  PoseMessage pose;     ///< valid for the pose types
  std::string health;   ///< JSON, for MessageType::Health
};

enum class DecodeStatus { Ok, NeedMore, Invalid };
/// Decodes the message at the front of `bytes`; on Ok `consumed` is its length. Invalid means the
/// stream is not (or no longer) a liod v2 stream: wrong magic, version or length.
DecodeStatus decode(std::span<const std::uint8_t> bytes, Message& out, std::size_t& consumed);

/// What a client has asked for with its request lines.
struct ClientMode {
  bool json = false;       ///< "json": one JSON object per line; "binary": binary messages
  bool scan_only = false;  ///< "scan": scan-rate poses only; "all": both rates
};

/// Turns the bytes a client sends, in whatever pieces they arrive, into request lines applied to
/// a ClientMode. Trailing '\r' and spaces are ignored; unknown lines are ignored.
class RequestReader {
 public:
  /// A line longer than this is not a request: it is dropped whole, up to its newline, without
  /// being buffered.
  static constexpr std::size_t kMaxLine = 1024;
  void feed(std::string_view bytes, ClientMode& mode);

 private:
  std::string line_;       // partial request line
  bool overlong_ = false;  // inside a line already longer than kMaxLine
};

/// The 6x6 pose covariance [position, rotation] from the filter's error-state covariance
/// ordered [rotation, position, velocity, gyro bias, accel bias, gravity direction] (any size >= 6).
Eigen::Matrix<double, 6, 6> pose_covariance_from_state(const Eigen::Ref<const Eigen::MatrixXd>& state_covariance);

}  // namespace liod::pose
