#include "liod/drivers/ouster_sample.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/point_records.hpp"
#include "text_fields.hpp"

namespace liod::drivers {
namespace {

/// A row-major 4x4 transform with its translation in millimetres, as Ouster's metadata gives them.
Eigen::Isometry3d transform_mm(const nlohmann::json& doc, const char* key, const std::string& file) {
  const auto it = doc.find(key);
  if (it == doc.end() || !it->is_array() || it->size() != 16) {
    throw InputError(file, 0, std::string(key) + ": expected a row-major 4x4 matrix of 16 numbers");
  }
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) {
    const auto& v = (*it)[static_cast<std::size_t>(i)];
    if (!v.is_number()) throw InputError(file, 0, std::string(key) + ": element " + std::to_string(i) + " is not a number");
    m(i / 4, i % 4) = v.get<double>();
  }
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = m.topLeftCorner<3, 3>();
  t.translation() = m.topRightCorner<3, 1>() * 1e-3;
  return t;
}

/// The comma-separated numbers of `line`, exactly `count` of them, else InputError.
template <std::size_t N>
void parse_row(std::string_view line, double (&values)[N], const std::string& file, std::size_t line_no,
               std::string_view columns) {
  const detail::FieldError err = detail::parse_fields(line, values);
  if (err.kind != detail::FieldError::Kind::None) throw InputError(file, line_no, detail::describe(err, columns));
}

}  // namespace

CloudScanConfig OusterMetadata::cloud_config() const {
  CloudScanConfig c;
  c.beam_elevations_deg = beam_altitude_deg;
  c.beam_origin_offset_m = beam_origin_offset_m;
  c.head_in_cloud = lidar_to_sensor;
  return c;
}

OusterMetadata read_ouster_metadata(const std::filesystem::path& path) {
  const std::string file = path.string();
  const nlohmann::json doc = nlohmann::json::parse(detail::read_text_file(path, "Ouster metadata"), nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) throw InputError(file, 0, "not a JSON object");
  OusterMetadata m;
  const auto altitudes = doc.find("beam_altitude_angles");
  if (altitudes == doc.end() || !altitudes->is_array() || altitudes->empty()) {
    throw InputError(file, 0, "beam_altitude_angles: expected an array of degrees");
  }
  for (const auto& a : *altitudes) {
    if (!a.is_number()) throw InputError(file, 0, "beam_altitude_angles: an element is not a number");
    m.beam_altitude_deg.push_back(a.get<double>());
  }
  const auto offset = doc.find("lidar_origin_to_beam_origin_mm");
  if (offset == doc.end() || !offset->is_number()) throw InputError(file, 0, "lidar_origin_to_beam_origin_mm: expected a number");
  m.beam_origin_offset_m = offset->get<double>() * 1e-3;
  m.lidar_to_sensor = transform_mm(doc, "lidar_to_sensor_transform", file);
  m.imu_to_sensor = transform_mm(doc, "imu_to_sensor_transform", file);
  return m;
}

std::vector<OusterFrame> read_ouster_frame_list(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string text = detail::read_text_file(path, "Ouster frame list");
  constexpr std::string_view kColumns = "index,frame_id,n_points,t_first_col_ns,t_last_col_ns,file";
  detail::LineSplitter lines(text);
  std::string_view line;
  std::size_t line_no = 0;
  if (!lines.next(line, line_no) || detail::trim(line) != kColumns) {
    throw InputError(file, 1, "expected the header '" + std::string(kColumns) + "'");
  }
  std::vector<OusterFrame> frames;
  while (lines.next(line, line_no)) {
    line = detail::trim(line);
    if (line.empty()) continue;
    const std::size_t last_comma = line.rfind(',');
    if (last_comma == std::string_view::npos) throw InputError(file, line_no, "expected " + std::string(kColumns));
    double v[5];
    parse_row(line.substr(0, last_comma), v, file, line_no, kColumns);
    OusterFrame f;
    f.frame_id = static_cast<std::uint64_t>(v[1]);
    f.first_column_s = v[3] * 1e-9;
    f.last_column_s = v[4] * 1e-9;
    f.file = path.parent_path() / std::string(detail::trim(line.substr(last_comma + 1)));
    frames.push_back(f);
  }
  return frames;
}

CloudSweep read_ouster_frame(const OusterFrame& frame, std::uint64_t sequence) {
  CloudSweep sweep;
  sweep.points = read_point_records(frame.file, kXyziTimeLayout);
  sweep.start_time = frame.first_column_s;
  sweep.end_time = frame.last_column_s;
  sweep.has_time = true;
  sweep.sequence = sequence;
  return sweep;
}

std::vector<ImuSample> read_ouster_imu(const std::filesystem::path& path) {
  const std::string file = path.string();
  const std::string text = detail::read_text_file(path, "Ouster IMU log");
  constexpr std::string_view kColumns = "t_accel_ns,t_gyro_ns,ax_mps2,ay_mps2,az_mps2,wx_radps,wy_radps,wz_radps";
  detail::LineSplitter lines(text);
  std::string_view line;
  std::size_t line_no = 0;
  if (!lines.next(line, line_no) || detail::trim(line) != kColumns) {
    throw InputError(file, 1, "expected the header '" + std::string(kColumns) + "'");
  }
  std::vector<ImuSample> samples;
  while (lines.next(line, line_no)) {
    line = detail::trim(line);
    if (line.empty()) continue;
    double v[8];
    parse_row(line, v, file, line_no, kColumns);
    ImuSample s;
    // The gyro's stamp: the deskew turns points with the rotation, which the gyro measures.
    s.time = v[1] * 1e-9;
    s.accel = Eigen::Vector3d(v[2], v[3], v[4]);
    s.gyro = Eigen::Vector3d(v[5], v[6], v[7]);
    if (!samples.empty() && s.time < samples.back().time) throw InputError(file, line_no, "time earlier than the previous sample's");
    samples.push_back(s);
  }
  return samples;
}

}  // namespace liod::drivers
