// Segment facings at the capture and the body heading from them (see facing.hpp).
#include "mocap/rig/facing.hpp"

#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {

std::string_view to_string(AlignSource s) {
  switch (s) {
    case AlignSource::none:
      return "none";
    case AlignSource::given:
      return "given";
    case AlignSource::body_heading:
      return "body_heading";
    case AlignSource::sensor_axis:
      return "sensor_axis";
    case AlignSource::site_normal:
      return "site_normal";
    case AlignSource::motion:
      return "motion";
    case AlignSource::hinge_axis:
      return "hinge_axis";
    case AlignSource::joint:
      return "joint";
    case AlignSource::heading_reset:
      return "heading_reset";
    case AlignSource::local_field:
      return "local_field";
    case AlignSource::saved:
      return "saved";
  }
  return "?";
}

bool replaces(const Facing& held, const Facing& candidate) {
  constexpr double kSameSourceDeadBandDeg = 1.0;
  if (!candidate.known()) return false;
  if (!held.known() || candidate.sigma_deg < held.sigma_deg) return true;
  // The same estimate from more evidence, where it moved.
  if (candidate.source == held.source)
    return std::abs(wrap_angle_rad(candidate.yaw_rad - held.yaw_rad)) * kDegPerRad >
           kSameSourceDeadBandDeg;
  return contradicts(held, candidate);
}

bool contradicts(const Facing& held, const Facing& candidate) {
  const auto assumed = [](AlignSource s) {
    return s == AlignSource::site_normal || s == AlignSource::sensor_axis;
  };
  const auto measured = [](AlignSource s) {
    return s == AlignSource::motion || s == AlignSource::hinge_axis;
  };
  if (!held.known() || !candidate.known() || !assumed(held.source) || !measured(candidate.source))
    return false;
  const double change_deg = std::abs(wrap_angle_rad(candidate.yaw_rad - held.yaw_rad)) * kDegPerRad;
  return change_deg > 3 * std::hypot(held.sigma_deg, candidate.sigma_deg);
}

Facing facing_from_axis(const PoseCapture& c, int s, const Eigen::Vector3d& forward_sensor,
                        double sigma_deg, AlignSource source) {
  Facing f;
  if (s < 0 || s >= kSegmentCount || !c.have[s] || forward_sensor.squaredNorm() == 0) return f;
  const Eigen::Vector3d e = c.q_earth_sensor[s] * forward_sensor.normalized();
  if (std::hypot(e.x(), e.y()) < 0.3) return f;  // near vertical: no yaw in it
  f.yaw_rad = heading_of_rad(e);
  f.sigma_deg = sigma_deg;
  f.source = source;
  return f;
}

Facing facing_from_site_normal(const PoseCapture& c, int s, const Eigen::Vector3d& normal_body) {
  // A strap's tilt off the normal (a few degrees) and the filter's heading error.
  constexpr double kSiteSigmaDeg = 8.0;
  // Farther than this from horizontal, the sensor's z axis is not along a horizontal normal.
  constexpr double kMaxNormalTiltDeg = 35.0;
  Facing f;
  if (s < 0 || s >= kSegmentCount || !c.have[s] || normal_body.squaredNorm() == 0) return f;
  const Eigen::Vector3d n_pose = q_body_segment_in_pose(c.pose, s) * normal_body.normalized();
  if (std::hypot(n_pose.x(), n_pose.y()) < 0.5) return f;  // vertical site: no yaw in it
  const Eigen::Vector3d n_earth = c.q_earth_sensor[s] * Eigen::Vector3d::UnitZ();
  if (std::abs(n_earth.z()) > std::sin(kMaxNormalTiltDeg * kRadPerDeg)) return f;
  f.yaw_rad = wrap_angle_rad(heading_of_rad(n_earth) - heading_of_rad(n_pose));
  f.sigma_deg = kSiteSigmaDeg;
  f.source = AlignSource::site_normal;
  return f;
}

BodyHeading body_heading_from_facings(const std::array<Facing, kSegmentCount>& facing,
                                      const std::array<bool, kSegmentCount>& use) {
  constexpr double kMaxSpreadDeg = 12.0;
  BodyHeading b;
  const auto circular_mean = [&](double center_rad, double max_dev_rad) {
    double sx = 0, sy = 0;
    b.used = 0;
    for (int i = 0; i < kSegmentCount; ++i) {
      b.agreed[i] = use[i] && facing[i].known() &&
                    std::abs(wrap_angle_rad(facing[i].yaw_rad - center_rad)) <= max_dev_rad;
      if (!b.agreed[i]) continue;
      sx += std::cos(facing[i].yaw_rad);
      sy += std::sin(facing[i].yaw_rad);
      ++b.used;
    }
    return std::atan2(sy, sx);
  };
  const double first = circular_mean(0, 4 * M_PI);
  if (b.used == 0) return b;
  const double h = circular_mean(first, kMaxSpreadDeg * kRadPerDeg);
  if (b.used > 0) b.heading_rad = h;
  return b;
}

std::optional<double> body_heading_from_arm_swing(const PoseCapture& npose,
                                                  const PoseCapture& tpose, std::string& why) {
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  int used = 0;
  for (Segment seg : {Segment::upper_arm_l, Segment::upper_arm_r}) {
    const int s = index(seg);
    if (!npose.have[s] || !tpose.have[s]) continue;
    const Eigen::AngleAxisd d(tpose.q_earth_sensor[s] * npose.q_earth_sensor[s].conjugate());
    const double ang_deg = d.angle() * kDegPerRad;
    if (ang_deg < 60 || ang_deg > 120) {
      why = std::string(name(seg)) + " rose " + std::to_string(ang_deg) +
            " deg between N- and T-pose (expect ~90)";
      return std::nullopt;
    }
    // The left arm rises about +x (forward), the right one about -x.
    axis += (seg == Segment::upper_arm_l ? 1.0 : -1.0) * d.axis();
    ++used;
  }
  if (used == 0 || std::hypot(axis.x(), axis.y()) < 0.3 * used) {
    why = "arm_swing needs an upper-arm sensor rotating about a horizontal axis";
    return std::nullopt;
  }
  return heading_of_rad(axis);
}

}  // namespace mocap::rig
