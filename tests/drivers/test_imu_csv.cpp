#include <gtest/gtest.h>

#include <clocale>
#include <cmath>
#include <iostream>
#include <fstream>
#include <limits>

#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/rs_helios_calibration.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

void write_text(const std::filesystem::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

/// The InputError message of reading `text` as an IMU log ("" if it reads fine).
std::string imu_error(const test::TempDir& dir, const std::string& text, std::size_t* line = nullptr) {
  const auto path = dir / "imu.csv";
  write_text(path, text);
  try {
    (void)read_imu_csv(path);
  } catch (const InputError& e) {
    if (line) *line = e.line();
    return e.what();
  }
  return "";
}

const std::string kHeader = "time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n";

TEST(ImuCsv, ReadsSamplesSkippingCommentsAndBlankLines) {
  test::TempDir dir;
  write_text(dir / "imu.csv", "# recorded by liod\n\n" + kHeader +
                                  "100.0,0.1,-0.2,0.3,0.01,0.02,9.81\r\n"
                                  "# a comment\n"
                                  "   \n"
                                  "100.005, +1e-3 ,2,3,4,5,6\n"
                                  "100.005,0,0,0,0,0,0");  // equal time allowed; no final newline
  const auto samples = read_imu_csv(dir / "imu.csv");
  ASSERT_EQ(samples.size(), 3U);
  EXPECT_DOUBLE_EQ(samples[0].time, 100.0);
  EXPECT_DOUBLE_EQ(samples[0].gyro.y(), -0.2);
  EXPECT_DOUBLE_EQ(samples[0].accel.z(), 9.81);
  EXPECT_DOUBLE_EQ(samples[1].gyro.x(), 1e-3);
  EXPECT_DOUBLE_EQ(samples[1].accel.z(), 6.0);
}

TEST(ImuCsv, WriterRoundTripsBitExactly) {
  test::TempDir dir;
  std::vector<ImuSample> in;
  for (int i = 0; i < 1000; ++i) {
    ImuSample s;
    s.time = 1.7e9 + i * 0.005 + 1e-7 / 3.0;
    s.gyro = Eigen::Vector3d(std::sin(i) * 0.1, std::cos(i) / 3.0, -1.0 / (i + 1));
    s.accel = Eigen::Vector3d(0.1 * i, -9.80665, std::numeric_limits<double>::min() * i);
    in.push_back(s);
  }
  {
    ImuCsvWriter w(dir / "out.csv");
    for (const auto& s : in) w.write(s);
  }
  const auto out = read_imu_csv(dir / "out.csv");
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_EQ(out[i].time, in[i].time);
    EXPECT_EQ(out[i].gyro, in[i].gyro);
    EXPECT_EQ(out[i].accel, in[i].accel);
  }
  ImuCsvWriter w(dir / "bad.csv");
  ImuSample nan_sample;
  nan_sample.gyro.x() = std::nan("");
  EXPECT_THROW(w.write(nan_sample), InputError);
}

TEST(ImuCsv, ErrorsNameFileAndLine) {
  test::TempDir dir;
  std::size_t line = 0;
  std::string e = imu_error(dir, kHeader + "1,0,0,0,0,0,9.8\n2,0,abc,0,0,0,9.8\n", &line);
  EXPECT_EQ(line, 3U);
  EXPECT_NE(e.find("imu.csv:3"), std::string::npos) << e;
  EXPECT_NE(e.find("'abc' is not a number"), std::string::npos) << e;

  e = imu_error(dir, kHeader + "1,0,0,0,0,0\n", &line);
  EXPECT_EQ(line, 2U);
  EXPECT_NE(e.find("found 6"), std::string::npos) << e;
  e = imu_error(dir, kHeader + "1,0,0,0,0,0,0,0\n", &line);
  EXPECT_NE(e.find("found 8"), std::string::npos) << e;

  e = imu_error(dir, kHeader + "1,0,0,nan,0,0,0\n", &line);
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;
  e = imu_error(dir, kHeader + "1,0,0,0,inf,0,0\n", &line);
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;

  e = imu_error(dir, kHeader + "2,0,0,0,0,0,0\n\n1.5,0,0,0,0,0,0\n", &line);
  EXPECT_EQ(line, 4U);
  EXPECT_NE(e.find("earlier than the previous"), std::string::npos) << e;

  e = imu_error(dir, "1,0,0,0,0,0,0\n", &line);
  EXPECT_NE(e.find("expected header"), std::string::npos) << e;
  e = imu_error(dir, "", &line);
  EXPECT_NE(e.find("empty"), std::string::npos) << e;
  e = imu_error(dir, kHeader + "1,0,0,0,,0,0\n", &line);
  EXPECT_NE(e.find("column 5"), std::string::npos) << e;
  EXPECT_THROW(ImuCsvReader(dir / "missing.csv"), InputError);
}

TEST(ImuCsv, ParsingIsLocaleIndependent) {
  // from_chars ignores the global locale; a decimal comma locale must not change the result.
  test::TempDir dir;
  write_text(dir / "imu.csv", kHeader + "1.5,0.25,0,0,0,0,9.5\n");
  const std::string previous = std::setlocale(LC_ALL, nullptr);
  const bool switched = std::setlocale(LC_ALL, "de_DE.UTF-8") != nullptr;
  const auto samples = read_imu_csv(dir / "imu.csv");
  std::setlocale(LC_ALL, previous.c_str());
  if (!switched) std::cout << "[ note ] de_DE.UTF-8 locale not installed; checked in the C locale only\n";
  ASSERT_EQ(samples.size(), 1U);
  EXPECT_DOUBLE_EQ(samples[0].gyro.x(), 0.25);
}

TEST(AnglesCsv, ReadsTheShippedFormat) {
  // nebula's files end rows with a tab and the last row has no newline.
  const AngleTable t = parse_angles_csv("14.94,-4.05\t\n13.03,3.61\t\n# note\n\n-8.01,3.57", "mem.csv");
  ASSERT_EQ(t.size(), 3U);
  EXPECT_DOUBLE_EQ(t.vertical_deg[2], -8.01);
  EXPECT_DOUBLE_EQ(t.horizontal_deg[0], -4.05);
  const auto file = test::robosense_dir() / "helios32_angles.csv";
  if (std::filesystem::exists(file)) {
    const AngleTable h32 = load_angles_csv(file);
    ASSERT_EQ(h32.size(), 32U);
    EXPECT_DOUBLE_EQ(h32.vertical_deg[31], -54.60);
    EXPECT_DOUBLE_EQ(h32.horizontal_deg[31], 4.80);
    const auto rings = rings_by_elevation(h32.vertical_deg);
    EXPECT_EQ(rings[0], 31);  // 14.94°: the top beam
    EXPECT_EQ(rings[31], 0);  // -54.6°: the bottom beam
    EXPECT_EQ(rings[16], 15); // -9.89° sits above -12.90° (slot 18)
  }
}

TEST(AnglesCsv, ErrorsNameTheLine) {
  try {
    (void)parse_angles_csv("1.0,2.0\n1.0,x2\n", "angles.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2U);
    EXPECT_EQ(e.file(), "angles.csv");
    EXPECT_NE(std::string(e.what()).find("angles.csv:2: column 2: 'x2' is not a number"), std::string::npos) << e.what();
  }
  try {
    (void)parse_angles_csv("1.0,2.0\n1.0,2.0,3.0\n", "angles.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2U);
    EXPECT_NE(std::string(e.what()).find("found 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)parse_angles_csv("1.0\n", "a.csv"), InputError);
  EXPECT_THROW((void)parse_angles_csv("\n# nothing\n", "a.csv"), InputError);
  EXPECT_THROW((void)parse_angles_csv("-95,0\n", "a.csv"), InputError);  // outside [-90, 180)
  EXPECT_THROW((void)load_angles_csv("/nonexistent/angles.csv"), InputError);
}

}  // namespace
}  // namespace liod::drivers
