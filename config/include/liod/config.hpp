#pragma once
// liod's whole configuration, composed of each library's own: the algorithm's (core), the
// drivers' and the daemon's. Filled and validated only by load_config(); every key a user sets
// is documented in config/liod.yaml, the advanced ones in config/examples/advanced.yaml.

#include <stdexcept>
#include <string>
#include <vector>

#include "liod/algorithm_config.hpp"
#include "liod/daemon/daemon_config.hpp"
#include "liod/drivers/sensor_config.hpp"

namespace liod {

struct Config : AlgorithmConfig, SensorConfig, DaemonConfig {};

/// Thrown for any configuration problem; the message names the file, the key and the value.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Loads the files in order, each overriding the keys it sets (e.g. the main file, then a
/// simulator's extrinsics.yaml), starting from the defaults. Throws ConfigError.
Config load_config(const std::vector<std::string>& paths);

/// Same, from YAML text (for tests); `origin` names it in errors.
Config load_config_from_string(const std::string& yaml_text, const std::string& origin);

}  // namespace liod
