#include "liod/drivers/input_error.hpp"

namespace liod::drivers {

// Built with append() rather than operator+: GCC 12 emits a false -Wrestrict for the latter
// (GCC bug 105329).
std::string InputError::format(const std::string& file, std::size_t line, const std::string& message) {
  std::string s;
  s.reserve(file.size() + message.size() + 24);
  s.append(file.empty() ? "<input>" : file);
  if (line > 0) s.append(":").append(std::to_string(line));
  s.append(": ").append(message);
  return s;
}

}  // namespace liod::drivers
