#pragma once
// Line splitting and locale-independent number parsing for the CSV-like text files liod reads
// (angle tables, IMU logs). std::from_chars: no locale, no iostream overhead (internal header).

#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "liod/drivers/input_error.hpp"

namespace liod::drivers::detail {

/// A whole text file; InputError naming it and `what` it is when it cannot be opened.
[[nodiscard]] inline std::string read_text_file(const std::filesystem::path& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), 0, std::string("cannot open ") + what);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

[[nodiscard]] inline std::string_view trim(std::string_view s) noexcept {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

/// Splits text into lines (LF or CRLF; a last line without newline counts), numbering from 1.
class LineSplitter {
 public:
  explicit LineSplitter(std::string_view text) noexcept : text_(text) {}
  bool next(std::string_view& line, std::size_t& line_no) noexcept {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line = text_.substr(pos_, stop - pos_);
    pos_ = stop + 1;
    line_no = ++count_;
    return true;
  }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t count_ = 0;
};

struct FieldError {
  enum class Kind { None, ColumnCount, NotANumber, NonFinite };
  Kind kind = Kind::None;
  std::size_t column = 0;  ///< 1-based column of a bad field; the found count for ColumnCount
  std::size_t expected = 0;
  std::string_view text;   ///< the offending field
};

/// Parses one number, the whole (trimmed) field; accepts a leading '+'.
[[nodiscard]] inline bool parse_double(std::string_view field, double& value) noexcept {
  field = trim(field);
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return false;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  return ec == std::errc() && ptr == field.data() + field.size();
}

/// Splits `line` at commas into exactly N finite numbers.
template <std::size_t N>
[[nodiscard]] FieldError parse_fields(std::string_view line, double (&values)[N]) noexcept {
  std::size_t column = 0;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    const std::string_view field =
        line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (column < N) {
      if (!parse_double(field, values[column])) return {FieldError::Kind::NotANumber, column + 1, N, trim(field)};
      if (!std::isfinite(values[column])) return {FieldError::Kind::NonFinite, column + 1, N, trim(field)};
    }
    ++column;
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (column != N) return {FieldError::Kind::ColumnCount, column, N, {}};
  return {};
}

[[nodiscard]] inline std::string describe(const FieldError& e, std::string_view columns) {
  switch (e.kind) {
    case FieldError::Kind::ColumnCount:
      return "expected " + std::to_string(e.expected) + " comma-separated columns (" + std::string(columns) +
             "), found " + std::to_string(e.column);
    case FieldError::Kind::NotANumber:
      return "column " + std::to_string(e.column) + ": '" + std::string(e.text) + "' is not a number";
    case FieldError::Kind::NonFinite:
      return "column " + std::to_string(e.column) + ": '" + std::string(e.text) + "' is not finite";
    case FieldError::Kind::None:
      break;
  }
  return "no error";
}

}  // namespace liod::drivers::detail
