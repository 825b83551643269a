// Calibration persistence: TOML text form written with full double precision, parsed with
// toml++ and validated (names, unit quaternions, version).
#include <toml++/toml.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mocap/skeleton/calibration.hpp"

#include "toml_io.hpp"

namespace mocap {

namespace {

using skeleton_toml::fail;

constexpr int kCalibrationVersion = 1;

std::string quat_text(const Eigen::Quaterniond& q) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "[%.17g, %.17g, %.17g, %.17g]", q.w(), q.x(), q.y(), q.z());
  return buf;
}

Eigen::Quaterniond read_quat(std::string_view source, const toml::node& n, std::string_view key) {
  const toml::array* a = n.as_array();
  if (!a || a->size() != 4) fail(source, n.source(), std::string(key) + " must be [w, x, y, z]");
  double v[4];
  for (int i = 0; i < 4; ++i) {
    const toml::node& e = *a->get(static_cast<size_t>(i));
    std::optional<double> d = e.value<double>();
    if (!d || !e.is_number() || !std::isfinite(*d))
      fail(source, e.source(), std::string(key) + " must hold finite numbers");
    v[i] = *d;
  }
  Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3)
    fail(source, n.source(), std::string(key) + " is not a unit quaternion");
  // Keep exactly what was written (serialised values are unit to ~1e-16); fix only sloppy input.
  return std::abs(q.norm() - 1.0) > 1e-12 ? q.normalized() : q;
}

double read_number(std::string_view source, const toml::node& n, std::string_view key) {
  std::optional<double> d = n.value<double>();
  if (!d || !n.is_number() || !std::isfinite(*d))
    fail(source, n.source(), std::string(key) + " must be a finite number");
  return *d;
}

}  // namespace

std::string serialize_calibration(const Calibration& c) {
  std::ostringstream os;
  char buf[64];
  os << "# mocap sensor-to-segment calibration\n[calibration]\nversion = " << kCalibrationVersion
     << "\nvalid = " << (c.valid ? "true" : "false") << "\npose = \"" << to_string(c.pose)
     << "\"\nheading_source = \"" << to_string(c.heading_source) << "\"\n";
  std::snprintf(buf, sizeof buf, "%.17g", c.heading_deg);
  os << "heading_deg = " << buf << "\n";
  std::snprintf(buf, sizeof buf, "%.17g", c.motion_deg);
  os << "motion_deg = " << buf << "\n";
  std::snprintf(buf, sizeof buf, "%.17g", c.gravity_error_deg);
  os << "gravity_error_deg = " << buf << "\n";
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!c.calibrated[i]) continue;
    os << "\n[segment." << kSegmentNames[i]
       << "]\nq_sensor_segment = " << quat_text(c.q_sensor_segment[i])
       << "\nq_correction = " << quat_text(c.q_correction[i]) << "\n";
  }
  return os.str();
}

Calibration parse_calibration(std::string_view text, std::string_view source) {
  const toml::table tbl = skeleton_toml::parse(text, source);
  Calibration c;
  bool have_header = false;
  for (auto&& [k, v] : tbl) {
    if (k == "calibration") {
      const toml::table* t = v.as_table();
      if (!t) fail(source, v.source(), "[calibration] must be a table");
      have_header = true;
      bool have_version = false;
      for (auto&& [ck, cv] : *t) {
        if (ck == "version") {
          std::optional<int64_t> ver = cv.value<int64_t>();
          if (!ver || !cv.is_integer() || *ver != kCalibrationVersion)
            fail(source, cv.source(), "unsupported calibration version (expected 1)");
          have_version = true;
        } else if (ck == "valid") {
          if (!cv.is_boolean()) fail(source, cv.source(), "valid must be true or false");
          c.valid = *cv.value<bool>();
        } else if (ck == "pose") {
          std::optional<std::string_view> s = cv.value<std::string_view>();
          if (s == "npose")
            c.pose = CalibrationPose::npose;
          else if (s == "tpose")
            c.pose = CalibrationPose::tpose;
          else
            fail(source, cv.source(), "pose must be \"npose\" or \"tpose\"");
        } else if (ck == "heading_source") {
          std::optional<std::string_view> s = cv.value<std::string_view>();
          bool found = false;
          for (HeadingSource h : {HeadingSource::pelvis_sensor, HeadingSource::mean_sensors,
                                  HeadingSource::explicit_heading, HeadingSource::arm_swing,
                                  HeadingSource::mount_normals})
            if (s && *s == to_string(h)) {
              c.heading_source = h;
              found = true;
            }
          if (!found) fail(source, cv.source(), "unknown heading_source");
        } else if (ck == "heading_deg") {
          c.heading_deg = read_number(source, cv, ck.str());
        } else if (ck == "motion_deg") {
          c.motion_deg = read_number(source, cv, ck.str());
        } else if (ck == "gravity_error_deg") {
          c.gravity_error_deg = read_number(source, cv, ck.str());
        } else {
          fail(source, ck.source(), "unknown key '" + std::string(ck.str()) + "' in [calibration]");
        }
      }
      if (!have_version) fail(source, v.source(), "[calibration] lacks version");
    } else if (k == "segment") {
      skeleton_toml::for_each_segment_table(
          source, v, [&](int i, const std::string& path, const toml::table& st) {
            bool have_q = false;
            for (auto&& [fk, fv] : st) {
              if (fk == "q_sensor_segment") {
                c.q_sensor_segment[i] = read_quat(source, fv, fk.str());
                have_q = true;
              } else if (fk == "q_correction") {
                c.q_correction[i] = read_quat(source, fv, fk.str());
              } else {
                fail(source, fk.source(), "unknown key '" + std::string(fk.str()) + "'");
              }
            }
            if (!have_q) fail(source, st.source(), path + " lacks q_sensor_segment");
            c.calibrated[i] = true;
          });
    } else {
      fail(source, k.source(), "unknown key '" + std::string(k.str()) + "'");
    }
  }
  if (!have_header) throw std::runtime_error(std::string(source) + ": missing [calibration] table");
  return c;
}

void save_calibration(const Calibration& c, const std::string& path) {
  // Written beside the target and renamed over it, so a reader (the recorder reads the file
  // while the daemon saves a refined calibration) sees the old or the new file, never half.
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error(path + ": cannot write calibration");
    out << serialize_calibration(c);
    out.close();
    if (!out) throw std::runtime_error(path + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error(path + ": cannot replace calibration file");
  }
}

Calibration load_calibration(const std::string& path) {
  return parse_calibration(skeleton_toml::read_file(path, "calibration"), path);
}

}  // namespace mocap
