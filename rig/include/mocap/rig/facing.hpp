// Where a segment faced at the calibration capture, and the body heading those facings give.
//
// A segment's facing is the earth yaw of its forward (x) axis in the capture's pose, in its own
// sensor's filter frame: together with the capture's up axis it fixes the sensor's mounting.
// Each source of it is one small function here: a configured sensor axis that points forward
// (facing_from_axis), a sensor lying flat on its site with z along the site's normal
// (facing_from_site_normal), a forward axis found from motion (mounting_motion.hpp,
// hinge_axis.hpp: also facing_from_axis). The body heading (the direction the person faces, in
// the shared earth frame of the sensors with a magnetometer) is the consensus of the facings of
// those sensors (body_heading_from_facings), the arms' rotation between an N- and a T-pose
// (body_heading_from_arm_swing), or given.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

#include "mocap/core/segments.hpp"
#include "mocap/rig/pose_capture.hpp"

namespace mocap::rig {

/// Where an alignment (a mounting or a heading) came from.
enum class AlignSource : uint8_t {
  none,           ///< not determined (yet)
  given,          ///< told by the user (calibration.heading = "explicit")
  body_heading,   ///< 9D: the sensor shares the earth frame and its segment faced the body
  sensor_axis,    ///< a configured sensor axis points forward (calibration.heading_axis)
  site_normal,    ///< the sensor's z axis along its site's outward normal
  motion,         ///< the mounting motion: the segment's tilt in a bow/squat/curl
  hinge_axis,     ///< the knee's flexion axis found from the two segments' tilt (hinge_axis.hpp)
  joint,          ///< 6D: kinematic constraints with the neighbouring segments
  heading_reset,  ///< a heading reset
  local_field,    ///< 9D: the filter's heading turned once the sensor left a local field
  saved,          ///< a calibration file
};
std::string_view to_string(AlignSource s);

/// A segment's facing at the capture (see above), its one-sigma and its source.
struct Facing {
  double yaw_rad = 0;
  double sigma_deg = 180;  ///< 180: unknown
  AlignSource source = AlignSource::none;
  bool known() const { return source != AlignSource::none; }
};

/// Whether `candidate` should replace `held`: nothing held; surer; the same source's newer
/// estimate where it moved by more than a degree; or where it contradicts `held`.
bool replaces(const Facing& held, const Facing& candidate);
/// `candidate` is measured (motion, hinge axis), `held` only assumed (a site normal, a sensor
/// axis), and the two disagree by more than three combined sigmas: the strap is not where it
/// was assumed to be.
bool contradicts(const Facing& held, const Facing& candidate);

/// The facing of `segment` from a sensor axis known to point along the segment's forward axis
/// in the pose; none when that axis is near vertical.
Facing facing_from_axis(const PoseCapture& c, int segment, const Eigen::Vector3d& forward_sensor,
                        double sigma_deg, AlignSource source);

/// The facing of `segment` from its sensor lying flat on its site: the sensor's z axis along
/// the site's outward normal, `normal_body` in the N-pose body frame. None when the normal is
/// vertical in the pose (top of the head, instep: no yaw in it) or when the sensor's z axis is
/// far from where the normal lies (> 35 deg off horizontal: not on that site, or not z out).
Facing facing_from_site_normal(const PoseCapture& c, int segment,
                               const Eigen::Vector3d& normal_body);

/// The body heading from the facings of the segments whose sensors share the earth frame
/// (`use`): their circular mean, then again over the facings within 12 deg of it (a strap's
/// tilt; a facing further off is a sensor whose filter took a local field for north, or not on
/// its site, and must not pull the body). None when no facing is used.
struct BodyHeading {
  std::optional<double> heading_rad;
  std::array<bool, kSegmentCount> agreed{};  ///< the facings the final mean used
  int used = 0;
};
BodyHeading body_heading_from_facings(const std::array<Facing, kSegmentCount>& facing,
                                      const std::array<bool, kSegmentCount>& use);

/// The body heading from the upper arms' rotation between an N-pose and a T-pose capture (the
/// arms rise about the body's forward axis): works for any mounting. None, with the reason in
/// `why`, without an upper-arm sensor rotating 60-120 deg about a horizontal axis.
std::optional<double> body_heading_from_arm_swing(const PoseCapture& npose,
                                                  const PoseCapture& tpose, std::string& why);

}  // namespace mocap::rig
