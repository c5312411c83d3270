#include "liod/drivers/rs_helios_model.hpp"

#include <algorithm>
#include <cctype>
#include <string>

namespace liod::drivers {

std::string_view to_string(HeliosModel m) noexcept {
  return m == HeliosModel::Helios16P ? "RS-Helios-16P" : "RS-Helios-5515";
}

std::optional<HeliosModel> parse_helios_model(std::string_view name) noexcept {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::erase(lower, '-');
  std::erase(lower, '_');
  if (lower == "helios5515" || lower == "helios32" || lower == "c32" || lower == "rshelios" ||
      lower == "rshelios5515")
    return HeliosModel::Helios5515;
  if (lower == "helios16p" || lower == "rshelios16p") return HeliosModel::Helios16P;
  return std::nullopt;
}

}  // namespace liod::drivers
