// Fuzz target: the IMU CSV log reader. The input is the file. Reading must end at the end of the
// file or with an InputError naming the file; every sample before that must be finite and in
// time order, as the reader promises the odometry.

#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  const liod::fuzz::MemoryFile file(data, size);
  bool have_previous = false;
  double previous = 0.0;
  try {
    liod::drivers::ImuCsvReader reader(file.path());
    liod::ImuSample s;
    while (reader.next(s)) {
      require(std::isfinite(s.time) && s.gyro.allFinite() && s.accel.allFinite(), "non-finite sample accepted");
      require(!have_previous || s.time >= previous, "sample earlier than the previous one accepted");
      have_previous = true;
      previous = s.time;
    }
  } catch (const liod::drivers::InputError& e) {
    require(std::string(e.what()).find(file.path()) != std::string::npos, "error message does not name the file");
  }
  return 0;
}
