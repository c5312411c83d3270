#pragma once
// A C stdio file that closes itself: the capture and log readers and writers use stdio for its
// buffering; what they do on a failed close (a full disk) they check before, at flush.

#include <cstdio>
#include <memory>

namespace liod::drivers {

struct FileCloser {
  void operator()(std::FILE* f) const noexcept { std::fclose(f); }
};

using CFile = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace liod::drivers
