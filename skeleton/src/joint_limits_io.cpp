// Joint limits from TOML: overrides on top of the anatomical defaults.
#include <toml++/toml.h>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "mocap/skeleton/config_tables.hpp"
#include "mocap/skeleton/joint_limits.hpp"

#include "toml_io.hpp"

namespace mocap {

namespace {

using skeleton_toml::fail;

int joint_index(std::string_view n) {
  for (int i = 0; i < kSegmentCount; ++i)
    if (kJointNames[i] == n || kSegmentNames[i] == n) return i;
  return -1;
}

void read_range(std::string_view source, const toml::node& n, std::string_view key, double& lo,
                double& hi) {
  const toml::array* a = n.as_array();
  if (!a || a->size() != 2) fail(source, n.source(), std::string(key) + " must be [min, max]");
  double v[2];
  for (int i = 0; i < 2; ++i) {
    const toml::node& e = *a->get(static_cast<size_t>(i));
    std::optional<double> d = e.value<double>();
    if (!d || !e.is_number() || !std::isfinite(*d))
      fail(source, e.source(), std::string(key) + " must hold finite numbers");
    v[i] = *d;
  }
  if (!(v[0] <= 0 && v[1] >= 0 && v[0] >= -180 && v[1] <= 180))
    fail(source, n.source(), std::string(key) + " must satisfy -180 <= min <= 0 <= max <= 180");
  lo = v[0];
  hi = v[1];
}

}  // namespace

void read_joint_limit_tables(const toml::node& joint, std::string_view source, JointLimits& L) {
  const toml::table* joints = joint.as_table();
  if (!joints) fail(source, joint.source(), "[joint] must be a table of joint tables");
  for (auto&& [jk, jv] : *joints) {
    const int i = joint_index(jk.str());
    if (i <= 0)
      fail(source, jk.source(), "unknown or unlimitable joint '" + std::string(jk.str()) + "'");
    const toml::table* jt = jv.as_table();
    if (!jt) fail(source, jv.source(), "joint." + std::string(jk.str()) + " must be a table");
    JointLimit& l = L.joint[i];
    for (auto&& [fk, fv] : *jt) {
      if (fk == "a_deg")
        read_range(source, fv, fk.str(), l.a_min_deg, l.a_max_deg);
      else if (fk == "b_deg")
        read_range(source, fv, fk.str(), l.b_min_deg, l.b_max_deg);
      else if (fk == "twist_deg")
        read_range(source, fv, fk.str(), l.twist_min_deg, l.twist_max_deg);
      else if (fk == "hinge") {
        if (!fv.is_boolean()) fail(source, fv.source(), "hinge must be true or false");
        l.hinge = *fv.value<bool>();
      } else if (fk == "limited") {
        if (!fv.is_boolean()) fail(source, fv.source(), "limited must be true or false");
        l.limited = *fv.value<bool>();
      } else
        fail(source, fk.source(), "unknown key '" + std::string(fk.str()) + "'");
    }
  }
  try {
    validate(L);
  } catch (const std::invalid_argument& e) {
    fail(source, joint.source(), e.what());
  }
}

JointLimits parse_joint_limits(std::string_view text, std::string_view source) {
  const toml::table tbl = skeleton_toml::parse(text, source);
  JointLimits L = default_joint_limits();
  for (auto&& [k, v] : tbl) {
    if (k != "joint") fail(source, k.source(), "unknown key '" + std::string(k.str()) + "'");
    read_joint_limit_tables(v, source, L);
  }
  return L;
}

JointLimits load_joint_limits(const std::string& path) {
  return parse_joint_limits(skeleton_toml::read_file(path, "joint limits file"), path);
}

}  // namespace mocap
