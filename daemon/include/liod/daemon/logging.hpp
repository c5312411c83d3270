#pragma once
#include <string>

namespace liod {

/// Sets up spdlog on stderr: colours only on a terminal, and no timestamps of its own when
/// journald is the reader (it stamps every line itself). Throws std::invalid_argument on an
/// unknown level name.
void setup_logging(const std::string& level);

}  // namespace liod
