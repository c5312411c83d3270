#include "liod/eval/canvas.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "liod/eval/font.hpp"
#include "liod/eval/png.hpp"

namespace liod::eval {

namespace {
constexpr int kGlyphW = 5;
constexpr int kGlyphH = 7;
constexpr int kAdvance = 6;  // one blank column between glyphs
}  // namespace

Canvas::Canvas(int width, int height, Rgb background) : width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("Canvas: empty size");
  pixels_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
  for (std::size_t i = 0; i < pixels_.size(); i += 3) {
    pixels_[i] = background.r;
    pixels_[i + 1] = background.g;
    pixels_[i + 2] = background.b;
  }
}

Rgb Canvas::at(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return {};
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) * 3;
  return {pixels_[i], pixels_[i + 1], pixels_[i + 2]};
}

void Canvas::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) * 3;
  pixels_[i] = c.r;
  pixels_[i + 1] = c.g;
  pixels_[i + 2] = c.b;
}

void Canvas::fill_rect(int x0, int y0, int x1, int y1, Rgb c) {
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width_ - 1);
  y1 = std::min(y1, height_ - 1);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) set(x, y, c);
  }
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb c, int width) {
  // Clamp far-away endpoints so a wild estimate cannot make Bresenham walk billions of pixels.
  const double lim = 4.0 * std::max(width_, height_);
  auto clamp = [lim](double v) { return std::clamp(v, -lim, lim); };
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  int ax = static_cast<int>(std::lround(clamp(x0)));
  int ay = static_cast<int>(std::lround(clamp(y0)));
  const int bx = static_cast<int>(std::lround(clamp(x1)));
  const int by = static_cast<int>(std::lround(clamp(y1)));
  const int dx = std::abs(bx - ax);
  const int dy = -std::abs(by - ay);
  const int sx = ax < bx ? 1 : -1;
  const int sy = ay < by ? 1 : -1;
  int err = dx + dy;
  const int lo = -(width - 1) / 2;
  const int hi = width / 2;
  while (true) {
    fill_rect(ax + lo, ay + lo, ax + hi, ay + hi, c);
    if (ax == bx && ay == by) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      ax += sx;
    }
    if (e2 <= dx) {
      err += dx;
      ay += sy;
    }
  }
}

void Canvas::disc(double cx, double cy, double radius, Rgb c) {
  const int r = static_cast<int>(std::ceil(radius));
  const int x0 = static_cast<int>(std::lround(cx));
  const int y0 = static_cast<int>(std::lround(cy));
  for (int y = -r; y <= r; ++y) {
    for (int x = -r; x <= r; ++x) {
      if (x * x + y * y <= radius * radius) set(x0 + x, y0 + y, c);
    }
  }
}

void Canvas::text(int x, int y, const std::string& s, Rgb c, int scale) {
  int pen = x;
  for (const char ch : s) {
    const auto* rows = glyph(ch);
    if (rows == nullptr) rows = glyph(static_cast<char>(std::toupper(static_cast<unsigned char>(ch))));
    if (rows != nullptr) {
      for (int r = 0; r < kGlyphH; ++r) {
        for (int col = 0; col < kGlyphW; ++col) {
          if (((*rows)[static_cast<std::size_t>(r)] >> (kGlyphW - 1 - col) & 1U) != 0U) {
            fill_rect(pen + col * scale, y + r * scale, pen + (col + 1) * scale - 1, y + (r + 1) * scale - 1, c);
          }
        }
      }
    }
    pen += kAdvance * scale;
  }
}

int Canvas::text_width(const std::string& s, int scale) {
  return s.empty() ? 0 : (static_cast<int>(s.size()) * kAdvance - 1) * scale;
}

int Canvas::text_height(int scale) { return kGlyphH * scale; }

void Canvas::write_png(const std::string& path) const { write_png_file(path, width_, height_, pixels_.data()); }

}  // namespace liod::eval
