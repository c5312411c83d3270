#pragma once
// The one exception type of liod_drivers: an input (file, row, packet stream) that cannot be used.
// Per-packet problems in a stream are counted, not thrown; this is for "the whole input is unusable"
// or "this row of a file the user wrote is wrong", where the message must name file, line and value.

#include <cstddef>
#include <stdexcept>
#include <string>

namespace liod::drivers {

class InputError : public std::runtime_error {
 public:
  /// `file` may be empty (in-memory input); `line` is 1-based, 0 when it does not apply.
  InputError(std::string file, std::size_t line, const std::string& message)
      : std::runtime_error(format(file, line, message)), file_(std::move(file)), line_(line) {}

  [[nodiscard]] const std::string& file() const noexcept { return file_; }
  [[nodiscard]] std::size_t line() const noexcept { return line_; }

 private:
  static std::string format(const std::string& file, std::size_t line, const std::string& message);

  std::string file_;
  std::size_t line_;
};

}  // namespace liod::drivers
