// The one translation unit that compiles stb_image_write. STATIC keeps its symbols private to this
// file, so another liod target that also embeds stb (or links Debian's libstb) cannot clash with it.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
// GCC's -Wnull-dereference fires after inlining, where the system-header exemption no longer applies;
// the flagged code is stb's own (its stretchy buffer does not check realloc), and only runs out of
// memory on images far beyond the few megabytes a plot takes.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <stb_image_write.h>
#pragma GCC diagnostic pop

#include <stdexcept>

#include "liod/eval/png.hpp"

namespace liod::eval {

void write_png_file(const std::string& path, int width, int height, const std::uint8_t* rgb) {
  if (stbi_write_png(path.c_str(), width, height, 3, rgb, width * 3) == 0) {
    throw std::runtime_error(path + ": cannot write PNG");
  }
}

}  // namespace liod::eval
