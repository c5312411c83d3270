#pragma once
// Bounded field-by-field reading of serialized records (internal header): the bag and MCAP
// containers (little-endian, packed), ROS 1 message serialization (little-endian, packed) and CDR
// (either byte order, each primitive aligned to its size from the start of the payload, strings
// with their NUL counted). Every read checks the bytes left first: a length field that points past
// the end is an InputError naming the input and the byte offset, never a read past the buffer or
// an allocation of the size the field claims.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers::detail {

struct CursorStyle {
  bool big_endian = false;
  /// CDR: a primitive of n bytes starts at a multiple of min(n, max_align) from the origin; 0 = packed.
  std::size_t max_align = 0;
  /// CDR strings: the length counts a terminating NUL, which is not part of the text.
  bool nul_terminated_strings = false;
};

class FieldCursor {
 public:
  /// `name` says what is read (file, record) in errors; `base_offset` is the bytes' offset in it.
  FieldCursor(std::span<const std::uint8_t> bytes, std::string name, std::uint64_t base_offset = 0, CursorStyle style = {})
      : bytes_(bytes), name_(std::move(name)), base_(base_offset), style_(style) {}

  std::uint8_t u8(const char* what) { return *need(1, what); }
  bool boolean(const char* what) { return u8(what) != 0; }
  std::uint16_t u16(const char* what) {
    align(2);
    return load16(need(2, what), style_.big_endian);
  }
  std::uint32_t u32(const char* what) {
    align(4);
    return load32(need(4, what), style_.big_endian);
  }
  std::int32_t i32(const char* what) { return static_cast<std::int32_t>(u32(what)); }
  std::uint64_t u64(const char* what) {
    align(8);
    return load64(need(8, what), style_.big_endian);
  }
  double f64(const char* what) { return std::bit_cast<double>(u64(what)); }

  std::span<const std::uint8_t> bytes(std::uint64_t n, const char* what) { return {need(n, what), static_cast<std::size_t>(n)}; }
  void skip(std::uint64_t n, const char* what) { need(n, what); }
  /// A string with a uint32 length before it.
  std::string string(const char* what) {
    const std::uint32_t n = u32(what);
    if (!style_.nul_terminated_strings) return text(n, what);
    if (n == 0) fail(std::string(what) + ": a CDR string of length 0 (it counts its NUL)");
    std::string s = text(n - 1, what);
    if (u8(what) != 0) fail(std::string(what) + ": CDR string without its terminating NUL");
    return s;
  }
  std::string text(std::uint64_t n, const char* what) {
    const std::uint8_t* p = need(n, what);
    return {reinterpret_cast<const char*>(p), static_cast<std::size_t>(n)};
  }

  [[nodiscard]] std::size_t remaining() const noexcept { return bytes_.size() - pos_; }
  [[nodiscard]] bool at_end() const noexcept { return pos_ == bytes_.size(); }
  [[nodiscard]] std::uint64_t offset() const noexcept { return base_ + pos_; }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(name_, 0, message + " (at byte offset " + std::to_string(offset()) + ")");
  }

 private:
  void align(std::size_t n) {
    if (style_.max_align == 0) return;
    const std::size_t a = n < style_.max_align ? n : style_.max_align;
    const std::size_t pad = (a - pos_ % a) % a;
    need(pad, "alignment padding");
  }
  const std::uint8_t* need(std::uint64_t n, const char* what) {
    if (n > remaining()) {
      fail(std::string(what) + ": needs " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " left");
    }
    const std::uint8_t* p = bytes_.data() + pos_;
    pos_ += static_cast<std::size_t>(n);
    return p;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  std::string name_;
  std::uint64_t base_;
  CursorStyle style_;
};

}  // namespace liod::drivers::detail
