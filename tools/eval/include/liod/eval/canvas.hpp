#pragma once
// A small RGB raster with just what the plots need: lines, dots, rectangles and 5x7 bitmap text.
// No plotting library is a Debian package we can rely on from C++, and the plots are simple.

#include <cstdint>
#include <string>
#include <vector>

namespace liod::eval {

struct Rgb {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
};

class Canvas {
 public:
  Canvas(int width, int height, Rgb background = {255, 255, 255});

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] const std::vector<std::uint8_t>& pixels() const { return pixels_; }  // row-major RGB
  [[nodiscard]] Rgb at(int x, int y) const;

  void set(int x, int y, Rgb c);  // ignores pixels outside the canvas
  void fill_rect(int x0, int y0, int x1, int y1, Rgb c);
  /// Bresenham line, `width` pixels thick (a square brush).
  void line(double x0, double y0, double x1, double y1, Rgb c, int width = 1);
  void disc(double cx, double cy, double radius, Rgb c);
  /// Top-left corner at (x, y); `scale` multiplies the 5x7 glyphs. Lower case without a glyph is drawn
  /// in upper case; characters without any glyph are skipped (one blank cell).
  void text(int x, int y, const std::string& s, Rgb c, int scale = 1);
  static int text_width(const std::string& s, int scale = 1);
  static int text_height(int scale = 1);

  /// PNG via stb_image_write; throws std::runtime_error naming the path when it cannot be written.
  void write_png(const std::string& path) const;

 private:
  int width_;
  int height_;
  std::vector<std::uint8_t> pixels_;
};

}  // namespace liod::eval
