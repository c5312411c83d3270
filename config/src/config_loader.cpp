// The one place where configuration is parsed and validated. Every key is declared once in
// declare_schema() with its type and admissible values; the loader rejects anything else.

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

#include "liod/config.hpp"

namespace liod {
namespace {

struct Source {
  std::string file;
  std::string key;
  const YAML::Node& node;
};

[[noreturn]] void fail(const Source& src, const std::string& what) {
  std::string value;
  try {
    if (src.node.IsScalar()) {
      value = src.node.Scalar();
    } else {
      std::ostringstream out;
      out << YAML::Dump(src.node);
      value = out.str();
    }
  } catch (const std::exception&) {
    value = "?";
  }
  std::ostringstream msg;
  msg << src.file;
  if (src.node.Mark().line >= 0) msg << ':' << src.node.Mark().line + 1;
  msg << ": key '" << src.key << "' = '" << value << "': " << what;
  throw ConfigError(msg.str());
}

using Setter = std::function<void(const Source&)>;

class Schema {
 public:
  void real(const std::string& key, double* target, double lo, double hi) {
    setters_[key] = [=](const Source& src) {
      const double v = scalar<double>(src, "a number");
      if (!std::isfinite(v) || v < lo || v > hi) {
        fail(src, "must be a number in [" + fmt(lo) + ", " + fmt(hi) + "]");
      }
      *target = v;
    };
  }
  void integer(const std::string& key, int* target, int lo, int hi) {
    setters_[key] = [=](const Source& src) {
      const int v = scalar<int>(src, "an integer");
      if (v < lo || v > hi) fail(src, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
      *target = v;
    };
  }
  void boolean(const std::string& key, bool* target) {
    setters_[key] = [=](const Source& src) { *target = scalar<bool>(src, "true or false"); };
  }
  void text(const std::string& key, std::string* target) {
    setters_[key] = [=](const Source& src) { *target = scalar<std::string>(src, "a string"); };
  }
  template <typename Enum>
  void choice(const std::string& key, Enum* target, std::map<std::string, Enum> options) {
    setters_[key] = [=](const Source& src) {
      const auto v = scalar<std::string>(src, "a string");
      const auto it = options.find(v);
      if (it == options.end()) {
        std::string allowed;
        for (const auto& [name, value] : options) allowed += (allowed.empty() ? "" : ", ") + name;
        fail(src, "must be one of: " + allowed);
      }
      *target = it->second;
    };
  }
  void vector3(const std::string& key, Eigen::Vector3d* target, double bound) {
    setters_[key] = [=](const Source& src) {
      const auto v = sequence(src, 3);
      for (double x : v) {
        if (std::abs(x) > bound) fail(src, "elements must lie in [-" + fmt(bound) + ", " + fmt(bound) + "]");
      }
      *target = Eigen::Vector3d(v[0], v[1], v[2]);
    };
  }
  void quaternion(const std::string& key, Eigen::Quaterniond* target) {
    setters_[key] = [=](const Source& src) {
      const auto v = sequence(src, 4);
      Eigen::Quaterniond q(v[3], v[0], v[1], v[2]);  // the file lists x, y, z, w
      if (std::abs(q.norm() - 1.0) > 1e-3) fail(src, "must be a unit quaternion [qx, qy, qz, qw]");
      *target = q.normalized();
    };
  }

  const Setter* find(const std::string& key) const {
    const auto it = setters_.find(key);
    return it == setters_.end() ? nullptr : &it->second;
  }

 private:
  static std::string fmt(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  }
  template <typename T>
  static T scalar(const Source& src, const char* expected) {
    if (!src.node.IsScalar()) fail(src, std::string("must be ") + expected);
    try {
      return src.node.as<T>();
    } catch (const YAML::Exception&) {
      fail(src, std::string("must be ") + expected);
    }
  }
  static std::vector<double> sequence(const Source& src, std::size_t n) {
    if (!src.node.IsSequence() || src.node.size() != n) {
      fail(src, "must be a list of " + std::to_string(n) + " numbers");
    }
    std::vector<double> out;
    for (const auto& element : src.node) {
      try {
        out.push_back(element.as<double>());
      } catch (const YAML::Exception&) {
        fail(src, "must be a list of " + std::to_string(n) + " numbers");
      }
      if (!std::isfinite(out.back())) fail(src, "must hold finite numbers");
    }
    return out;
  }

  std::map<std::string, Setter> setters_;
};

Schema declare_schema(Config& c) {
  Schema s;
  constexpr double kInf = std::numeric_limits<double>::max();
  s.text("log.level", &c.log.level);

  s.choice("lidar.model", &c.lidar.model,
           {{"helios5515", LidarModel::kHelios5515}, {"helios16p", LidarModel::kHelios16P}});
  s.integer("lidar.msop_port", &c.lidar.msop_port, 1, 65535);
  s.integer("lidar.difop_port", &c.lidar.difop_port, 1, 65535);
  s.text("lidar.angles_csv", &c.lidar.angles_csv);
  s.real("lidar.min_range_m", &c.lidar.min_range_m, 0.0, 10.0);
  s.real("lidar.max_range_m", &c.lidar.max_range_m, 1.0, 500.0);
  s.real("lidar.split_azimuth_deg", &c.lidar.split_azimuth_deg, 0.0, 359.99);

  s.real("imu.rate_hz", &c.imu.rate_hz, 10.0, 10000.0);
  s.real("imu.gyro_noise_density", &c.imu.gyro_noise_density, 1e-7, 1.0);
  s.real("imu.accel_noise_density", &c.imu.accel_noise_density, 1e-6, 10.0);
  s.real("imu.gyro_bias_random_walk", &c.imu.gyro_bias_random_walk, 1e-9, 1.0);
  s.real("imu.accel_bias_random_walk", &c.imu.accel_bias_random_walk, 1e-9, 10.0);
  s.real("imu.gravity_m_s2", &c.imu.gravity_m_s2, 9.7, 9.9);
  s.real("imu.max_gap_s", &c.imu.max_gap_s, 0.001, 10.0);

  s.vector3("extrinsics.lidar_to_imu.translation_m", &c.extrinsics.lidar_to_imu_translation, 10.0);
  s.quaternion("extrinsics.lidar_to_imu.rotation_xyzw", &c.extrinsics.lidar_to_imu_rotation);
  s.real("extrinsics.lidar_time_offset_s", &c.extrinsics.lidar_time_offset_s, -1.0, 1.0);

  auto& o = c.odometry;
  s.choice("odometry.deskew", &o.deskew,
           {{"imu", DeskewMode::kImu}, {"constant_velocity", DeskewMode::kConstantVelocity}, {"none", DeskewMode::kNone}});
  s.choice("odometry.curvature", &o.curvature,
           {{"adaptive", CurvatureMode::kAdaptive}, {"fixed", CurvatureMode::kFixed}});
  s.choice("odometry.keyframe_gating", &o.keyframe_gating,
           {{"hausdorff", KeyframeGating::kHausdorff}, {"distance_angle", KeyframeGating::kDistanceAngle}});
  s.real("odometry.min_range_m", &o.min_range_m, 0.0, 50.0);
  s.real("odometry.max_range_m", &o.max_range_m, 5.0, 500.0);
  s.real("odometry.occlusion_jump_m", &o.occlusion_jump_m, 0.01, 10.0);
  s.real("odometry.edge_curvature", &o.edge_curvature, 0.0, 10.0);
  s.real("odometry.plane_curvature", &o.plane_curvature, 0.0, 10.0);
  s.integer("odometry.sectors_per_ring", &o.sectors_per_ring, 1, 64);
  s.integer("odometry.max_edges_per_sector", &o.max_edges_per_sector, 0, 1000);
  s.real("odometry.plane_voxel_m", &o.plane_voxel_m, 0.01, 5.0);
  s.real("odometry.edge_voxel_m", &o.edge_voxel_m, 0.01, 5.0);
  s.real("odometry.map_voxel_m", &o.map_voxel_m, 0.1, 10.0);
  s.integer("odometry.map_points_per_voxel", &o.map_points_per_voxel, 1, 1000);
  s.real("odometry.map_min_point_spacing_m", &o.map_min_point_spacing_m, 0.0, 5.0);
  s.integer("odometry.max_iterations", &o.max_iterations, 1, 50);
  s.real("odometry.lidar_noise_m", &o.lidar_noise_m, 1e-4, 10.0);
  s.real("odometry.max_correspondence_m", &o.max_correspondence_m, 0.05, 20.0);
  s.real("odometry.keyframe_distance_m", &o.keyframe_distance_m, 0.0, 100.0);
  s.real("odometry.keyframe_angle_deg", &o.keyframe_angle_deg, 0.0, 180.0);
  s.real("odometry.hausdorff_threshold_m", &o.hausdorff_threshold_m, 0.0, 100.0);
  s.real("odometry.hausdorff_voxel_m", &o.hausdorff_voxel_m, 0.05, 10.0);
  s.integer("odometry.window_keyframes", &o.window_keyframes, 1, 1000);
  s.real("odometry.degeneracy_eigenvalue", &o.degeneracy_eigenvalue, 0.0, kInf);
  s.real("odometry.init_gyro_bias_std", &o.init_gyro_bias_std, 1e-6, 1.0);
  s.real("odometry.init_accel_bias_std", &o.init_accel_bias_std, 1e-6, 10.0);
  s.real("odometry.init_velocity_std", &o.init_velocity_std, 1e-3, 100.0);
  s.real("odometry.init_tilt_std_deg", &o.init_tilt_std_deg, 0.01, 45.0);

  s.boolean("backend.enabled", &c.backend.enabled);
  s.text("output.pose_socket", &c.output.pose_socket);
  s.text("output.state_dir", &c.output.state_dir);
  return s;
}

void apply(const Schema& schema, const YAML::Node& node, const std::string& prefix, const std::string& file) {
  if (!node.IsMap()) {
    const Source src{file, prefix.empty() ? "<top level>" : prefix, node};
    fail(src, "must be a mapping of keys");
  }
  for (const auto& entry : node) {
    const std::string key = prefix.empty() ? entry.first.as<std::string>() : prefix + "." + entry.first.as<std::string>();
    const YAML::Node& value = entry.second;
    if (const Setter* setter = schema.find(key)) {
      (*setter)(Source{file, key, value});
    } else if (value.IsMap()) {
      apply(schema, value, key, file);
    } else {
      fail(Source{file, key, value}, "unknown key (see config/liod.yaml for the keys liod knows)");
    }
  }
}

void validate_relations(const Config& c, const std::string& origin) {
  auto reject = [&](const std::string& key, double value, const std::string& why) {
    std::ostringstream msg;
    msg << origin << ": key '" << key << "' = '" << value << "': " << why;
    throw ConfigError(msg.str());
  };
  if (c.lidar.max_range_m <= c.lidar.min_range_m) {
    reject("lidar.max_range_m", c.lidar.max_range_m, "must exceed lidar.min_range_m");
  }
  if (c.odometry.max_range_m <= c.odometry.min_range_m) {
    reject("odometry.max_range_m", c.odometry.max_range_m, "must exceed odometry.min_range_m");
  }
  if (c.odometry.plane_curvature >= c.odometry.edge_curvature) {
    reject("odometry.plane_curvature", c.odometry.plane_curvature, "must be below odometry.edge_curvature");
  }
  static const char* kLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  bool level_ok = false;
  for (const char* level : kLevels) level_ok = level_ok || c.log.level == level;
  if (!level_ok) {
    throw ConfigError(origin + ": key 'log.level' = '" + c.log.level +
                      "': must be one of trace, debug, info, warn, error, critical, off");
  }
}

void apply_text(Config& config, const std::string& text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (root.IsNull()) return;  // an empty file changes nothing
  const Schema schema = declare_schema(config);
  apply(schema, root, "", origin);
}

}  // namespace

Config load_config_from_string(const std::string& yaml_text, const std::string& origin) {
  Config config;
  apply_text(config, yaml_text, origin);
  validate_relations(config, origin);
  return config;
}

Config load_config(const std::vector<std::string>& paths) {
  Config config;
  std::string origins;
  for (const auto& path : paths) {
    std::ifstream in(path);
    if (!in) throw ConfigError(path + ": cannot open configuration file");
    std::ostringstream text;
    text << in.rdbuf();
    apply_text(config, text.str(), path);
    origins += (origins.empty() ? "" : " + ") + path;
  }
  validate_relations(config, origins.empty() ? "<defaults>" : origins);
  return config;
}

}  // namespace liod
