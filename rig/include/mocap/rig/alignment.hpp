// Each segment's alignment: how its sensor's orientation becomes the segment's,
//
//   q_earth_segment = Rz(heading) * q_earth_sensor * q_sensor_segment,
//
// a heading (a yaw in front of the sensor's filter frame: for a 6D sensor, its own heading
// frame turned onto the body's; a heading reset) and a mounting (the sensor's rotation on its
// segment). This class is their one owner: every change of either goes through one of its
// methods, each with its source and a one-sigma, and the skeleton only ever reads the
// Calibration it builds.
//
// The mounting is fixed by the calibration capture (immutable, pose_capture.hpp) up to a yaw:
// the capture gives the segment's up axis in the sensor frame; the segment's facing at the
// capture (facing.hpp) gives the rest. For a sensor sharing the earth frame (9D) the segment
// faced the body heading; for a sensor with a heading frame of its own (6D) its facing gives
// both its mounting and its heading (heading = body heading - facing). Two turns change an
// alignment later, both about the vertical and written once (alignment.cpp):
//  - turn_heading: the sensor's frame turned against the body's (6D drift): the heading turns,
//    the mounting stays;
//  - turn_mounting: the sensor's frame had turned before the capture (its facing was wrong, or
//    its filter's frame turned since): the mounting turns so that the segment keeps its pose at
//    the capture, q_ss' = q_ss T^-1 Y^-1 T (T the segment's orientation in the pose).
// A new facing of a 6D sensor is both (the pose at the capture is kept). Every change applies at
// once: the published pose eases onto one found while tracking (Skeleton::set_calibration).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/rig/facing.hpp"
#include "mocap/rig/pose_capture.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::rig {

/// One segment's alignment with where each part came from and how sure it is.
struct SegmentAlignment {
  bool aligned = false;  ///< calibrated (a capture or a saved calibration)
  /// The sensor's filter has a heading frame of its own (6D, or a sensor without magnetometer
  /// in a 9D rig): its heading is this alignment's business.
  bool own_frame = false;
  /// The mounting's yaw: the segment's facing at the capture in its sensor's frame.
  Facing facing;
  double heading_rad = 0;  ///< the yaw in front of the sensor's orientation
  AlignSource heading_source = AlignSource::none;
  double heading_sigma_deg = 180;  ///< of the segment's heading relative to the body's
  /// Turns from motion refused as implausible (a found heading is never turned over).
  uint32_t rejected_turns = 0;
  /// Far turns accepted as the correction of a wrong first facing (turn_guard.hpp).
  uint32_t corrected_turns = 0;
  /// The sensor's own heading frame was lost (lose_heading: a dropout) and is not yet found
  /// again; how many times that happened.
  bool heading_lost = false;
  uint32_t lost_headings = 0;
};

class Alignment {
 public:
  /// A running estimate from motion that would turn a found alignment by more than this is a
  /// flip or misleading motion, never a strap that moved: refused (reject_turn).
  static constexpr double kImplausibleTurnDeg = 45.0;

  Alignment();

  /// A calibration from a capture: every segment with a sensor gets its mounting tilt from the
  /// capture's up axis and its yaw from the body heading (sensors sharing the earth frame) or
  /// from its facing (own-frame sensors; one without a facing keeps its sensor's frame, heading
  /// unknown). `heading_source` is the calibration's record of the body heading's source,
  /// `body_source` and `body_sigma_deg` the alignment's (none, 180: unknown).
  void align(const PoseCapture& capture, double body_heading_rad, HeadingSource heading_source,
             AlignSource body_source, double body_sigma_deg,
             const std::array<Facing, kSegmentCount>& facing,
             const std::array<bool, kSegmentCount>& own_frame);
  /// A saved calibration (no capture behind it: facings unknown, sources `saved`).
  void load(const Calibration& c);
  void clear();

  /// A better facing for segment s, e.g. from motion. Own-frame sensor: mounting and heading
  /// turn together (the segment keeps its pose at the capture). Sensor sharing the earth frame:
  /// recorded only (its mounting follows the body heading). Returns the facing's change, rad.
  double set_facing(int s, const Facing& f);
  /// The body faced `heading_rad` at the capture: the mountings of the sensors sharing the
  /// earth frame turn, the own-frame sensors' headings turn with it.
  void set_body_heading(double heading_rad, AlignSource source, double sigma_deg);
  /// Turns the segment's heading by yaw_rad (its sensor's frame drifted against the body's, or
  /// a lost heading found again); the mounting stays.
  void turn_heading(int s, double yaw_rad, AlignSource source, double sigma_deg);
  /// The sensor's heading alignment was off by yaw_rad at the capture: heading and mounting
  /// turn together, the segment keeps its pose at the capture (a better facing, -change).
  void realign(int s, double yaw_rad, AlignSource source, double sigma_deg);
  /// The sensor's filter frame turned by yaw_rad since the capture (a local field left
  /// behind): the mounting turns so that the segment keeps its pose at the capture.
  void turn_mounting(int s, double yaw_rad, AlignSource source);
  /// Segment s's sensor lost its own heading frame (silent long enough that its filter could
  /// not follow, or a tracker that rebooted): the heading is kept as the best guess but marked
  /// lost (source none, sigma 180, counted) until regain_heading. Own-frame sensors only; the
  /// mounting stays (the strap did not move); turn_heading turns it meanwhile.
  void lose_heading(int s);
  /// Segment s's lost heading is found again (its turns since were the finding).
  void regain_heading(int s);
  /// A turn of segment s from motion was refused as implausible (counted, reported).
  void reject_turn(int s) {
    if (s >= 0 && s < kSegmentCount) ++seg_[static_cast<size_t>(s)].rejected_turns;
  }
  /// A far turn of segment s corrected a wrong first facing (counted, reported; the facing
  /// itself changes through set_facing).
  void correct_turn(int s) {
    if (s >= 0 && s < kSegmentCount) ++seg_[static_cast<size_t>(s)].corrected_turns;
  }
  /// Heading reset (the person stands facing forward): every segment in `have` takes the
  /// pelvis's earth yaw (its twist about the vertical; the circular mean without a pelvis
  /// sensor), or target_heading_rad when given.
  void reset_heading(const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_sensor,
                     const std::array<bool, kSegmentCount>& have,
                     const double* target_heading_rad = nullptr);

  /// The calibration the skeleton uses (rebuilt on every change).
  const Calibration& calibration() const { return calib_; }
  /// Counts every change (a caller that saves the calibration compares it with its last save).
  uint64_t revision() const { return revision_; }
  const SegmentAlignment& segment(int s) const { return seg_[static_cast<size_t>(s)]; }
  double body_heading_rad() const { return body_heading_rad_; }
  AlignSource body_heading_source() const { return body_source_; }
  double body_heading_sigma_deg() const { return body_sigma_deg_; }
  /// The capture the alignment came from (false after load()).
  bool has_capture() const { return have_capture_; }
  const PoseCapture& capture() const { return capture_; }

 private:
  /// The segment's orientation in the capture's pose, earth frame (T above).
  Eigen::Quaterniond pose_orientation(int s) const;
  void changed(int s);

  PoseCapture capture_;
  bool have_capture_ = false;
  double body_heading_rad_ = 0;
  AlignSource body_source_ = AlignSource::none;
  double body_sigma_deg_ = 180;
  std::array<SegmentAlignment, kSegmentCount> seg_{};
  Calibration calib_;
  uint64_t revision_ = 0;
};

}  // namespace mocap::rig
