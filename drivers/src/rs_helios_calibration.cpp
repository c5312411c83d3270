#include "liod/drivers/rs_helios_calibration.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "liod/drivers/input_error.hpp"
#include "text_fields.hpp"

namespace liod::drivers {

AngleTable load_angles_csv(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), 0, "cannot open angle calibration file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_angles_csv(text.str(), path.string());
}

AngleTable parse_angles_csv(std::string_view text, const std::string& name) {
  AngleTable table;
  detail::LineSplitter lines(text);
  std::string_view line;
  std::size_t line_no = 0;
  double values[2];
  while (lines.next(line, line_no)) {
    line = detail::trim(line);
    if (line.empty() || line.front() == '#') continue;
    const detail::FieldError err = detail::parse_fields(line, values);
    if (err.kind != detail::FieldError::Kind::None)
      throw InputError(name, line_no, detail::describe(err, "vertical_deg,horizontal_deg"));
    // The same bounds DIFOP tables are held to (spec §6): [-90°, 180°).
    for (double v : values) {
      if (v < -90.0 || v >= 180.0)
        throw InputError(name, line_no, "angle in '" + std::string(line) + "' outside [-90, 180) degrees");
    }
    table.vertical_deg.push_back(values[0]);
    table.horizontal_deg.push_back(values[1]);
  }
  if (table.size() == 0) throw InputError(name, 0, "angle calibration file has no rows");
  return table;
}

std::vector<std::uint16_t> rings_by_elevation(std::span<const double> vertical_deg) {
  std::vector<std::uint16_t> rings(vertical_deg.size());
  rings_by_elevation(vertical_deg, rings);
  return rings;
}

void rings_by_elevation(std::span<const double> vertical_deg, std::span<std::uint16_t> rings) noexcept {
  for (std::size_t i = 0; i < vertical_deg.size(); ++i) {
    std::size_t rank = 0;
    for (std::size_t j = 0; j < vertical_deg.size(); ++j) {
      if (vertical_deg[j] < vertical_deg[i] || (vertical_deg[j] == vertical_deg[i] && j < i)) ++rank;
    }
    rings[i] = static_cast<std::uint16_t>(rank);
  }
}

}  // namespace liod::drivers
