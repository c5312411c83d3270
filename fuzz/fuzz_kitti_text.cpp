// Fuzz target: KITTI raw's text fields (kitti_raw.hpp). The first byte picks the parser (even: a
// timestamp line, odd: an OXTS line), the rest is the line. Parsing must end with a value or an
// InputError naming the file: a timestamp a finite number of seconds with the calendar's bounds
// (0000-01-01 to 9999-12-31), an OXTS sample with finite rates and accelerations.

#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/kitti_raw.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const std::string name = "timestamps.txt";
  try {
    if ((data[0] & 1U) == 0) {
      const double t = liod::drivers::parse_kitti_timestamp(text, name, 1);
      require(std::isfinite(t) && t > -62.2e9 && t < 253.5e9, "a timestamp outside the calendar's years 0-9999");
    } else {
      const liod::ImuSample s = liod::drivers::parse_oxts_line(text, 1.0, name);
      require(s.accel.allFinite() && s.gyro.allFinite(), "a sample that is not finite");
    }
  } catch (const liod::drivers::InputError& e) {
    require(std::string(e.what()).find(name) != std::string::npos, "error message does not name the file");
  }
  return 0;
}
