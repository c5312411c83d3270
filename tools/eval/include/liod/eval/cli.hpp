#pragma once
// liod-eval's command line, as a function so the tests can drive it without spawning a process.

#include <iosfwd>

namespace liod::eval {

/// Returns the process exit code: 0 success, 1 bad input or evaluation failure, CLI11's codes for
/// usage errors (--help prints usage and returns 0).
int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace liod::eval
