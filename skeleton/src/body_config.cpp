// Body model config: TOML parsing of the editable form and the build of the runtime form.
#include <toml++/toml.h>
#include <cmath>
#include <stdexcept>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/config_tables.hpp"

#include "toml_io.hpp"

namespace mocap {

namespace {

using skeleton_toml::fail;

Eigen::Vector3d read_vec3(std::string_view source, const toml::node& n, std::string_view key,
                          double limit_m) {
  const toml::array* a = n.as_array();
  if (!a || a->size() != 3)
    fail(source, n.source(), std::string(key) + " must be an array of 3 numbers");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const toml::node& e = *a->get(static_cast<size_t>(i));
    std::optional<double> d = e.value<double>();
    if (!d || !e.is_number()) fail(source, e.source(), std::string(key) + " must hold numbers");
    if (!std::isfinite(*d) || std::abs(*d) > limit_m)
      fail(source, e.source(), std::string(key) + " value out of range (|v| <= 2 m)");
    v[i] = *d;
  }
  return v;
}

}  // namespace

void read_body_segments(const toml::node& segment, std::string_view source, BodyModelConfig& cfg) {
  skeleton_toml::for_each_segment_table(
      source, segment, [&](int i, const std::string& path, const toml::table& st) {
        for (auto&& [fk, fv] : st) {
          if (fk == "joint_offset_m")
            cfg.joint_offset_m[i] = read_vec3(source, fv, fk.str(), 2.0);
          else if (fk == "end_offset_m")
            cfg.end_offset_m[i] = read_vec3(source, fv, fk.str(), 2.0);
          else
            fail(source, fk.source(), "unknown key '" + std::string(fk.str()) + "' in " + path);
        }
      });
}

BodyModelConfig parse_body_config(std::string_view text, std::string_view source) {
  const toml::table tbl = skeleton_toml::parse(text, source);
  BodyModelConfig cfg;
  for (auto&& [k, v] : tbl) {
    if (k == "height_m") {
      std::optional<double> h = v.value<double>();
      if (!h || !v.is_number()) fail(source, v.source(), "height_m must be a number");
      if (!std::isfinite(*h) || *h < kMinBodyHeightM || *h > kMaxBodyHeightM)
        fail(source, v.source(), "height_m out of range (0.5 .. 2.6 m)");
      cfg.height_m = *h;
    } else if (k == "segment") {
      read_body_segments(v, source, cfg);
    } else {
      fail(source, k.source(), "unknown key '" + std::string(k.str()) + "'");
    }
  }
  return cfg;
}

BodyModelConfig load_body_config(const std::string& path) {
  return parse_body_config(skeleton_toml::read_file(path, "body config"), path);
}

BodyModel::BodyModel(const BodyModelConfig& cfg)
    : dims_(body_dimensions_from_height(cfg.height_m)) {
  for (int i = 0; i < kSegmentCount; ++i) {
    if (cfg.joint_offset_m[i]) dims_.joint_offset_m[i] = *cfg.joint_offset_m[i];
    if (cfg.end_offset_m[i]) dims_.end_offset_m[i] = *cfg.end_offset_m[i];
  }
}

BodyModel::BodyModel(const BodyDimensions& dims) : dims_(dims) {}

}  // namespace mocap
