#pragma once
// A generated scenario: the world and the plan of the drive through it, from route kind and seed.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "liod/sim/path.hpp"
#include "liod/sim/world.hpp"

namespace liod::sim {

enum class RouteKind { Urban, Loop, Figure8, Highway, Tunnel };

std::optional<RouteKind> parse_route(std::string_view name);
const char* route_name(RouteKind kind);

enum class StartMode { Default, Rolling, Static };

struct SceneRequest {
  RouteKind route = RouteKind::Urban;
  std::uint64_t seed = 1;
  double duration = 60.0;
  double max_speed = 12.0;
  StartMode start = StartMode::Default;
  double static_seconds = 3.0;
  /// A second drive through the same world (city routes: same seed, duration and max speed): the
  /// route is drawn from this seed, starting on a random street in a random direction.
  std::optional<std::uint64_t> route_seed;
};

struct Scene {
  World world;
  DrivePlan plan;
  double road_roughness = 32e-6;  // ISO 8608 G0 for the suspension model
  std::string summary;            // one line for scenario.yaml
};

Scene generate_scene(const SceneRequest& request);

}  // namespace liod::sim
