// Fuzz target: the configuration loader (YAML, schema, relations). The input is the file's text.
// Whatever it holds, the loader must return a Config or throw ConfigError naming the file: the
// daemon reports exactly that to the user and exits.

#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "liod/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)liod::load_config_from_string(text, "fuzz.yaml");
  } catch (const liod::ConfigError& e) {
    liod::fuzz::require(std::string(e.what()).find("fuzz.yaml") != std::string::npos,
                        "configuration error does not name the file");
  }
  return 0;
}
