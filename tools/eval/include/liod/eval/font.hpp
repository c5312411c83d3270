#pragma once
// A 5x7 bitmap font: digits, upper-case letters, the lower-case letters used in units and axis names
// (m, s, x, y, z) and some punctuation.

#include <array>
#include <cstdint>

namespace liod::eval {

/// Seven rows, bit 4 = leftmost column. nullptr when the character has no glyph.
const std::array<std::uint8_t, 7>* glyph(char c);

}  // namespace liod::eval
