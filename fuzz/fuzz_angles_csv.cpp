// Fuzz target: the angle calibration CSV reader (lidar.angles_csv: `vertical_deg,horizontal_deg`
// per channel). The input is the file's text. Parsing must end with a table or an InputError
// naming the file; a table has one vertical and one horizontal angle per row, each finite and in
// the [-90, 180) degrees DIFOP tables are held to (spec §6), and its rings (elevation ranks) are a
// permutation of the rows, as the decoder relies on.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_support.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/rs_helios_calibration.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  const std::string name = "angles.csv";
  try {
    const liod::drivers::AngleTable t =
        liod::drivers::parse_angles_csv(std::string_view(reinterpret_cast<const char*>(data), size), name);
    require(t.size() > 0 && t.horizontal_deg.size() == t.size(), "table rows and columns do not match");
    for (std::size_t i = 0; i < t.size(); ++i) {
      for (const double v : {t.vertical_deg[i], t.horizontal_deg[i]})
        require(std::isfinite(v) && v >= -90.0 && v < 180.0, "angle outside [-90, 180) accepted");
    }
    std::vector<std::uint16_t> rings = liod::drivers::rings_by_elevation(t.vertical_deg);
    std::sort(rings.begin(), rings.end());
    for (std::size_t i = 0; i < rings.size(); ++i) require(rings[i] == i, "rings are not a permutation of the rows");
  } catch (const liod::drivers::InputError& e) {
    require(std::string(e.what()).find(name) != std::string::npos, "error message does not name the file");
  }
  return 0;
}
