#include "liod/drivers/imu_csv.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>

#include "liod/drivers/input_error.hpp"
#include "text_fields.hpp"

namespace liod::drivers {
namespace {

constexpr std::size_t kColumns = 7;

bool header_matches(std::string_view line) {
  std::string_view expected = kImuCsvHeader;
  for (;;) {
    const std::size_t a = line.find(',');
    const std::size_t b = expected.find(',');
    if (detail::trim(line.substr(0, a)) != expected.substr(0, b)) return false;
    if (a == std::string_view::npos || b == std::string_view::npos) return a == b;
    line.remove_prefix(a + 1);
    expected.remove_prefix(b + 1);
  }
}

}  // namespace

ImuCsvReader::ImuCsvReader(const std::filesystem::path& path) : path_(path.string()), in_(path, std::ios::binary) {
  if (!in_) throw InputError(path_, 0, "cannot open IMU log");
  std::string_view line;
  if (!next_data_line(line)) throw InputError(path_, 0, "IMU log is empty (expected header " + std::string(kImuCsvHeader) + ")");
  if (!header_matches(line))
    throw InputError(path_, line_no_, "expected header '" + std::string(kImuCsvHeader) + "', found '" + std::string(line) + "'");
}

bool ImuCsvReader::next_data_line(std::string_view& line) {
  while (std::getline(in_, line_)) {
    ++line_no_;
    line = detail::trim(line_);
    if (line.empty() || line.front() == '#') continue;
    return true;
  }
  return false;
}

bool ImuCsvReader::next(ImuSample& sample) {
  std::string_view line;
  if (!next_data_line(line)) return false;
  double v[kColumns];
  const detail::FieldError err = detail::parse_fields(line, v);
  if (err.kind != detail::FieldError::Kind::None) throw InputError(path_, line_no_, detail::describe(err, kImuCsvHeader));
  if (have_previous_ && v[0] < previous_time_) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "time %.9f s is earlier than the previous sample's %.9f s", v[0], previous_time_);
    throw InputError(path_, line_no_, buf);
  }
  have_previous_ = true;
  previous_time_ = v[0];
  sample.time = v[0];
  sample.gyro = Eigen::Vector3d(v[1], v[2], v[3]);
  sample.accel = Eigen::Vector3d(v[4], v[5], v[6]);
  return true;
}

std::vector<ImuSample> read_imu_csv(const std::filesystem::path& path) {
  ImuCsvReader reader(path);
  std::vector<ImuSample> samples;
  ImuSample s;
  while (reader.next(s)) samples.push_back(s);
  return samples;
}

ImuCsvWriter::ImuCsvWriter(const std::filesystem::path& path) : path_(path.string()) {
  file_.reset(std::fopen(path_.c_str(), "wb"));
  if (!file_) throw InputError(path_, 0, std::string("cannot create IMU log: ") + std::strerror(errno));
  const std::string header = std::string(kImuCsvHeader) + "\n";
  if (std::fwrite(header.data(), 1, header.size(), file_.get()) != header.size())
    throw InputError(path_, 0, "cannot write IMU log header");
}

ImuCsvWriter::~ImuCsvWriter() = default;

void ImuCsvWriter::write(const ImuSample& s) {
  const double values[kColumns] = {s.time, s.gyro.x(), s.gyro.y(), s.gyro.z(), s.accel.x(), s.accel.y(), s.accel.z()};
  char buf[kColumns * 32];
  char* p = buf;
  char* const end = buf + sizeof buf;
  for (std::size_t i = 0; i < kColumns; ++i) {
    // The reader refuses NaN/inf, so refuse to write a log it could not read back.
    if (!std::isfinite(values[i]))
      throw InputError(path_, 0, "non-finite IMU value in sample at t=" + std::to_string(s.time));
    if (i != 0) *p++ = ',';
    // Shortest representation that round-trips: what the reader parses is bit-identical.
    const auto r = std::to_chars(p, end - 1, values[i]);
    if (r.ec != std::errc()) throw InputError(path_, 0, "cannot format IMU value");
    p = r.ptr;
  }
  *p++ = '\n';
  const auto n = static_cast<std::size_t>(p - buf);
  if (std::fwrite(buf, 1, n, file_.get()) != n) throw InputError(path_, 0, std::string("write failed: ") + std::strerror(errno));
}

void ImuCsvWriter::flush() {
  if (std::fflush(file_.get()) != 0) throw InputError(path_, 0, std::string("flush failed: ") + std::strerror(errno));
}

}  // namespace liod::drivers
