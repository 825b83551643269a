// calibrate(): a judged capture -> facings -> body heading -> alignment, and the report of what
// could not be determined (see calibrate.hpp). One small function per source of a facing or
// of the body heading.
#include "mocap/rig/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {
namespace {

using Facings = std::array<Facing, kSegmentCount>;
using Flags = std::array<bool, kSegmentCount>;

/// A strap's tilt plus the filter's heading error, for a sensor axis said to point forward.
constexpr double kAxisSigmaDeg = 10.0;

Facings site_facings(const PoseCapture& c, const CalibrationSetup& setup) {
  Facings f{};
  for (int s = 0; s < kSegmentCount; ++s)
    f[s] = facing_from_site_normal(c, s, setup.site_normal_body[s]);
  return f;
}

/// pelvis_sensor: the pelvis's facing from its configured axis; mean_sensors: every sensor's.
Facings axis_facings(const PoseCapture& c, const CalibrationSetup& setup, bool every_sensor) {
  Facings f{};
  for (int s = 0; s < kSegmentCount; ++s)
    if (every_sensor || s == index(Segment::pelvis))
      f[s] = facing_from_axis(c, s, setup.heading_axis_sensor, kAxisSigmaDeg,
                              AlignSource::sensor_axis);
  return f;
}

/// How far each segment stood from the pose where its site normal shows it (its tilt), deg.
std::array<double, kSegmentCount> pose_deviation(const PoseCapture& c,
                                                 const CalibrationSetup& setup) {
  std::array<double, kSegmentCount> dev;
  dev.fill(-1);
  for (int s = 0; s < kSegmentCount; ++s) {
    const Eigen::Vector3d& n_body = setup.site_normal_body[s];
    if (!c.have[s] || n_body.squaredNorm() == 0) continue;
    const Eigen::Vector3d n_pose = q_body_segment_in_pose(c.pose, s) * n_body.normalized();
    const Eigen::Vector3d n_earth = c.q_earth_sensor[s] * Eigen::Vector3d::UnitZ();
    dev[s] = std::abs(std::asin(std::clamp(n_earth.z(), -1.0, 1.0)) -
                      std::asin(std::clamp(n_pose.z(), -1.0, 1.0))) *
             kDegPerRad;
  }
  return dev;
}

/// The body heading the configured source gives, or none (with the reason in `why`).
std::optional<double> configured_body_heading(const PoseCapture& c, const CalibrationSetup& setup,
                                              const Facings& facing, const Flags& shared,
                                              const PoseCapture* npose, std::string& why) {
  switch (setup.heading) {
    case HeadingSource::explicit_heading:
      return setup.explicit_heading_deg * kRadPerDeg;
    case HeadingSource::arm_swing:
      return npose ? body_heading_from_arm_swing(*npose, c, why) : std::nullopt;
    case HeadingSource::pelvis_sensor:
      if (!facing[index(Segment::pelvis)].known())
        why = c.have[0] ? "the pelvis sensor's heading axis is near vertical"
                        : "heading from the pelvis needs a pelvis sensor";
      else if (shared[index(Segment::pelvis)])
        return facing[index(Segment::pelvis)].yaw_rad;
      break;
    case HeadingSource::mean_sensors:
    case HeadingSource::mount_normals:
      if (auto b = body_heading_from_facings(facing, shared); b.heading_rad) return b.heading_rad;
      why = setup.heading == HeadingSource::mount_normals
                ? "no sensor on a site with a known horizontal normal agrees on it"
                : "no sensor with a horizontal heading axis";
      break;
  }
  return std::nullopt;
}

AlignSource body_source(HeadingSource h, bool known) {
  if (!known) return AlignSource::none;
  switch (h) {
    case HeadingSource::explicit_heading:
      return AlignSource::given;
    case HeadingSource::arm_swing:
      return AlignSource::motion;
    case HeadingSource::mount_normals:
      return AlignSource::site_normal;
    case HeadingSource::pelvis_sensor:
    case HeadingSource::mean_sensors:
      break;
  }
  return AlignSource::sensor_axis;
}

std::string joined_names(const Flags& which) {
  std::string out;
  for (int s = 0; s < kSegmentCount; ++s)
    if (which[s]) out += (out.empty() ? "" : ", ") + std::string(name(static_cast<Segment>(s)));
  return out;
}

}  // namespace

CalibrationResult calibrate(const PoseCapturer::Result& captured, const CalibrationSetup& setup,
                            const Flags& own_frame, const PoseCapture* npose, Alignment& out) {
  CalibrationResult r;
  const PoseCapture& c = captured.capture;
  r.motion_deg = c.motion_deg;
  r.gravity_error_deg = c.gravity_error_deg;
  r.samples = c.samples;
  if (!captured.ok) {
    r.message = captured.message;
    return r;
  }
  if (setup.heading == HeadingSource::arm_swing && !npose) {
    r.status = CalibrationStatus::need_tpose;
    r.message = "N-pose captured; now hold the T-pose";
    return r;
  }
  r.pose_deviation_deg = pose_deviation(c, setup);
  const bool axis_source =
      setup.heading == HeadingSource::pelvis_sensor || setup.heading == HeadingSource::mean_sensors;
  r.facing = axis_source ? axis_facings(c, setup, setup.heading == HeadingSource::mean_sensors)
                         : site_facings(c, setup);
  Flags shared{};
  for (int s = 0; s < kSegmentCount; ++s)
    shared[s] = c.have[s] && !own_frame[s];
  std::string why;
  std::optional<double> heading = configured_body_heading(c, setup, r.facing, shared, npose, why);
  // Without a sensor sharing the earth frame (6D) the body heading is a convention: +x.
  const bool any_shared = std::find(shared.begin(), shared.end(), true) != shared.end();
  if (!any_shared && !heading) heading = 0.0;
  if (setup.heading == HeadingSource::arm_swing && !heading) {
    r.message = "calibration refused: " + why;
    return r;
  }
  r.body_heading_known = heading.has_value();
  const double h = heading.value_or(0.0);

  // Sensors sharing the earth frame far off the body heading: a local field taken for north
  // (a magnet, steel), or the pose turned there; reported, for the tracker to watch.
  std::ostringstream off;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (!shared[s] || !r.facing[s].known() || !r.body_heading_known) continue;
    const double d = wrap_angle_rad(r.facing[s].yaw_rad - h);
    if (std::abs(d) <= CalibrationResult::kLocalFieldDeg * kRadPerDeg) continue;
    r.heading_off_normal_rad[s] = d;
    off << (off.tellp() > 0 ? ", " : "") << name(static_cast<Segment>(s)) << " "
        << std::lround(d * kDegPerRad) << " deg";
  }
  out.align(c, h, setup.heading,
            any_shared ? body_source(setup.heading, r.body_heading_known) : AlignSource::given,
            !r.body_heading_known ? 180.0
            : any_shared          ? kAxisSigmaDeg
                                  : 0.0,
            r.facing, own_frame);
  r.calibration = out.calibration();
  r.status = CalibrationStatus::ok;

  std::ostringstream msg;
  msg.precision(3);
  msg << "calibrated in " << to_string(c.pose) << ", heading " << h * kDegPerRad
      << " deg, worst motion " << c.worst_motion_deg << " deg";
  int worst = -1;
  for (int s = 0; s < kSegmentCount; ++s)
    if (r.pose_deviation_deg[s] >= 0 &&
        (worst < 0 || r.pose_deviation_deg[s] > r.pose_deviation_deg[worst]))
      worst = s;
  if (worst >= 0)
    msg << "; furthest from the " << to_string(c.pose) << ": " << name(static_cast<Segment>(worst))
        << " tilted " << r.pose_deviation_deg[worst]
        << " deg (reported only: the tracked motion is unaffected)";
  if (off.tellp() > 0)
    msg << "; heading off the site normal (a magnet or steel near it, or the pose turned there): "
        << off.str() << " (corrected if the field turns by as much once it moves away)";
  if (!r.body_heading_known)
    msg << "; body heading not determined (" << why
        << "): found from the mounting motion (mocapctl calibrate mounting) or walking";
  Flags unknown{};
  for (int s = 0; s < kSegmentCount; ++s)
    unknown[s] = c.have[s] && own_frame[s] && !r.facing[s].known();
  if (const std::string u = joined_names(unknown); !u.empty())
    msg << "; mounting yaw and heading from motion: " << u;
  r.message = msg.str();
  return r;
}

}  // namespace mocap::rig
