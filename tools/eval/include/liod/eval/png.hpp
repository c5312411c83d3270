#pragma once

#include <cstdint>
#include <string>

namespace liod::eval {

/// 8-bit RGB, rows top to bottom; throws std::runtime_error naming the path on failure.
void write_png_file(const std::string& path, int width, int height, const std::uint8_t* rgb);

}  // namespace liod::eval
