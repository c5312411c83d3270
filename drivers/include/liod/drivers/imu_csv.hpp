#pragma once
// IMU log files: a header line `time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z`, then one
// sample per line (time in seconds on the IMU clock, angular rate rad/s, specific force m/s², IMU
// frame). Blank lines and lines starting with '#' are ignored. Numbers are parsed with
// std::from_chars (locale-independent) and written in the shortest form that reads back exactly.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "liod/drivers/c_file.hpp"
#include "liod/types.hpp"

namespace liod::drivers {

inline constexpr std::string_view kImuCsvHeader = "time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z";

/// Streams samples from an IMU CSV. Every error throws InputError naming file and line: a missing
/// or wrong header, a wrong column count, a field that is not a number, NaN/inf, or a time earlier
/// than the previous sample's (equal times are allowed).
class ImuCsvReader {
 public:
  explicit ImuCsvReader(const std::filesystem::path& path);
  /// Next sample; false at the end of the file.
  bool next(ImuSample& sample);
  [[nodiscard]] std::size_t line_number() const noexcept { return line_no_; }

 private:
  bool next_data_line(std::string_view& line);

  std::string path_;
  std::ifstream in_;
  std::string line_;
  std::size_t line_no_ = 0;
  bool have_previous_ = false;
  double previous_time_ = 0.0;
};

/// Reads a whole IMU CSV (see ImuCsvReader for the errors it throws).
[[nodiscard]] std::vector<ImuSample> read_imu_csv(const std::filesystem::path& path);

/// Writes an IMU CSV (header first). Throws InputError when the file cannot be written.
class ImuCsvWriter {
 public:
  explicit ImuCsvWriter(const std::filesystem::path& path);
  ~ImuCsvWriter();
  ImuCsvWriter(const ImuCsvWriter&) = delete;
  ImuCsvWriter& operator=(const ImuCsvWriter&) = delete;

  void write(const ImuSample& sample);
  void flush();

 private:
  std::string path_;
  CFile file_;
};

}  // namespace liod::drivers
