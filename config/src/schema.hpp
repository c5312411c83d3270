#pragma once
// The loader's schema: every key declared once with its type and admissible values; a value is
// checked and stored by the key's setter, and anything undeclared is rejected.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "liod/config.hpp"

namespace liod::config_schema {

struct Source {
  std::string file;
  std::string key;
  const YAML::Node& node;
};

[[noreturn]] inline void fail(const Source& src, const std::string& what) {
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

  /// A list of CAN signal mappings (drivers.imu.can_signals): each entry a mapping with
  /// quantity, id, [id_mask], byte, [bytes], [endian], [signed], [scale], [offset].
  void can_signals(const std::string& key, std::vector<CanSignalConfig>* target) {
    setters_[key] = [=](const Source& src) {
      if (!src.node.IsSequence()) fail(src, "must be a list of signal mappings");
      std::vector<CanSignalConfig> out;
      for (std::size_t i = 0; i < src.node.size(); ++i) {
        const YAML::Node& e = src.node[i];
        const std::string k = key + "[" + std::to_string(i) + "]";
        if (!e.IsMap()) fail(Source{src.file, k, e}, "must be a mapping");
        CanSignalConfig sig;
        bool have_id = false;
        bool have_quantity = false;
        for (const auto& f : e) {
          if (!f.first.IsScalar()) fail(Source{src.file, k, f.first}, "keys must be plain names");
          const std::string name = f.first.as<std::string>();
          const Source fs{src.file, k + "." + name, f.second};
          auto u32 = [&](std::uint32_t limit) {
            const long long v = scalar<long long>(fs, "an integer");
            if (v < 0 || v > static_cast<long long>(limit)) fail(fs, "must be an integer in [0, " + std::to_string(limit) + "]");
            return static_cast<std::uint32_t>(v);
          };
          if (name == "quantity") {
            sig.quantity = scalar<std::string>(fs, "a string");
            static const char* kQ[] = {"gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"};
            bool ok = false;
            for (const char* q : kQ) ok = ok || sig.quantity == q;
            if (!ok) fail(fs, "must be one of gyro_x, gyro_y, gyro_z, accel_x, accel_y, accel_z");
            have_quantity = true;
          } else if (name == "id") {
            sig.can_id = u32(0x1FFFFFFF);
            have_id = true;
          } else if (name == "id_mask") {
            sig.id_mask = u32(0x1FFFFFFF);
          } else if (name == "byte") {
            sig.byte_offset = static_cast<int>(u32(63));
          } else if (name == "bytes") {
            sig.length_bytes = static_cast<int>(u32(4));
            if (sig.length_bytes != 1 && sig.length_bytes != 2 && sig.length_bytes != 4) fail(fs, "must be 1, 2 or 4");
          } else if (name == "endian") {
            const auto v = scalar<std::string>(fs, "a string");
            if (v != "little" && v != "big") fail(fs, "must be little or big");
            sig.big_endian = v == "big";
          } else if (name == "signed") {
            sig.is_signed = scalar<bool>(fs, "true or false");
          } else if (name == "scale" || name == "offset") {
            const double v = scalar<double>(fs, "a number");
            if (!std::isfinite(v)) fail(fs, "must be finite");
            (name == "scale" ? sig.scale : sig.offset) = v;
          } else {
            fail(fs, "unknown key (quantity, id, id_mask, byte, bytes, endian, signed, scale, offset)");
          }
        }
        if (!have_id || !have_quantity) fail(Source{src.file, k, e}, "needs at least 'quantity' and 'id'");
        out.push_back(sig);
      }
      *target = out;
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

}  // namespace liod::config_schema
