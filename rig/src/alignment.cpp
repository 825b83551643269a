// Alignment: the one owner of every segment's mounting and heading (see alignment.hpp).
#include "mocap/rig/alignment.hpp"

#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {
namespace {

/// The mounting turned by yaw about the vertical so that the segment keeps its orientation t
/// in the capture's pose although its sensor's frame turned by yaw: q_ss T^-1 Y^-1 T.
Eigen::Quaterniond turned_mounting(const Eigen::Quaterniond& q_sensor_segment,
                                   const Eigen::Quaterniond& t, double yaw_rad) {
  return (q_sensor_segment * t.conjugate() * yaw_rotation(-yaw_rad) * t).normalized();
}

}  // namespace

Alignment::Alignment() {
  clear();
}

void Alignment::clear() {
  capture_ = PoseCapture{};
  have_capture_ = false;
  body_heading_rad_ = 0;
  body_source_ = AlignSource::none;
  body_sigma_deg_ = 180;
  seg_.fill(SegmentAlignment{});
  calib_ = Calibration{};
  ++revision_;
}

Eigen::Quaterniond Alignment::pose_orientation(int s) const {
  return yaw_rotation(calib_.heading_deg * kRadPerDeg) * q_body_segment_in_pose(calib_.pose, s);
}

void Alignment::changed(int s) {
  if (s >= 0) calib_.q_correction[s].normalize();
  ++revision_;
}

void Alignment::align(const PoseCapture& capture, double body_heading_rad,
                      HeadingSource heading_source, AlignSource body_source, double body_sigma_deg,
                      const std::array<Facing, kSegmentCount>& facing,
                      const std::array<bool, kSegmentCount>& own_frame) {
  capture_ = capture;
  have_capture_ = true;
  body_heading_rad_ = body_heading_rad;
  body_source_ = body_source;
  body_sigma_deg_ = body_sigma_deg;
  calib_ = Calibration{};
  Calibration& c = calib_;
  c.valid = true;
  c.pose = capture.pose;
  c.heading_source = heading_source;
  c.heading_deg = body_heading_rad * kDegPerRad;
  c.motion_deg = capture.worst_motion_deg;
  c.gravity_error_deg = capture.worst_gravity_error_deg;
  const Eigen::Quaterniond q_earth_body = yaw_rotation(body_heading_rad);
  for (int s = 0; s < kSegmentCount; ++s) {
    SegmentAlignment& a = seg_[s];
    a = SegmentAlignment{};
    if (!capture.have[s]) continue;
    a.aligned = true;
    a.own_frame = own_frame[s];
    a.facing = facing[s];
    if (a.own_frame && a.facing.known()) {
      // The sensor's own heading frame turned so that its segment faces the body heading.
      a.heading_rad = wrap_angle_rad(body_heading_rad - a.facing.yaw_rad);
      a.heading_source = a.facing.source;
      a.heading_sigma_deg = a.facing.sigma_deg;
      c.q_correction[s] = yaw_rotation(a.heading_rad);
    } else if (!a.own_frame) {
      a.heading_source = AlignSource::body_heading;
      a.heading_sigma_deg = 0;
    }
    c.calibrated[s] = true;
    const Eigen::Quaterniond q_earth_sensor = c.q_correction[s] * capture.q_earth_sensor[s];
    c.q_sensor_segment[s] =
        (q_earth_sensor.conjugate() * q_earth_body * q_body_segment_in_pose(c.pose, s))
            .normalized();
  }
  ++revision_;
}

void Alignment::load(const Calibration& c) {
  clear();
  calib_ = c;
  body_heading_rad_ = c.heading_deg * kRadPerDeg;
  body_source_ = AlignSource::saved;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (!c.valid || !c.calibrated[s]) continue;
    SegmentAlignment& a = seg_[s];
    a.aligned = true;
    a.heading_rad = yaw_of_rad(c.q_correction[s]);
    a.heading_source = AlignSource::saved;
    a.facing.source = AlignSource::saved;
  }
  ++revision_;
}

double Alignment::set_facing(int s, const Facing& f) {
  if (s < 0 || s >= kSegmentCount || !f.known() || !std::isfinite(f.yaw_rad)) return 0;
  SegmentAlignment& a = seg_[s];
  if (!a.aligned || !have_capture_) return 0;
  // The facing the alignment holds now (an own-frame sensor without one kept its own frame,
  // which is the facing body heading - heading at the capture).
  const double old_rad = a.facing.known() ? a.facing.yaw_rad : body_heading_rad_ - a.heading_rad;
  const double change = wrap_angle_rad(f.yaw_rad - old_rad);
  // An own-frame sensor's frame turns by -change onto the body; the segment keeps its capture
  // pose.
  if (a.own_frame) realign(s, -change, f.source, f.sigma_deg);  // changes the calibration
  a.facing = f;
  return change;
}

void Alignment::set_body_heading(double heading_rad, AlignSource source, double sigma_deg) {
  if (!calib_.valid || !std::isfinite(heading_rad)) return;
  const double change = wrap_angle_rad(heading_rad - body_heading_rad_);
  for (int s = 0; s < kSegmentCount; ++s) {
    SegmentAlignment& a = seg_[s];
    if (!a.aligned) continue;
    if (a.own_frame) {
      calib_.q_correction[s] = yaw_rotation(change) * calib_.q_correction[s];
      a.heading_rad = wrap_angle_rad(a.heading_rad + change);
      calib_.q_correction[s].normalize();
    } else {
      // The segment faced the new heading at the capture: its mounting turns by the change.
      calib_.q_sensor_segment[s] =
          turned_mounting(calib_.q_sensor_segment[s], pose_orientation(s), -change);
    }
  }
  body_heading_rad_ = heading_rad;
  body_source_ = source;
  body_sigma_deg_ = sigma_deg;
  calib_.heading_deg = heading_rad * kDegPerRad;
  ++revision_;
}

void Alignment::turn_heading(int s, double yaw_rad, AlignSource source, double sigma_deg) {
  if (s < 0 || s >= kSegmentCount || !seg_[s].aligned || !std::isfinite(yaw_rad)) return;
  SegmentAlignment& a = seg_[s];
  calib_.q_correction[s] = yaw_rotation(yaw_rad) * calib_.q_correction[s];
  a.heading_rad = wrap_angle_rad(a.heading_rad + yaw_rad);
  a.heading_source = source;
  a.heading_sigma_deg = sigma_deg;
  changed(s);
}

void Alignment::lose_heading(int s) {
  if (s < 0 || s >= kSegmentCount || !seg_[s].aligned || !seg_[s].own_frame) return;
  SegmentAlignment& a = seg_[s];
  a.heading_source = AlignSource::none;
  a.heading_sigma_deg = 180;
  a.heading_lost = true;
  ++a.lost_headings;
  ++revision_;
}

void Alignment::regain_heading(int s) {
  if (s < 0 || s >= kSegmentCount || !seg_[s].heading_lost) return;
  seg_[s].heading_lost = false;
  ++revision_;
}

void Alignment::realign(int s, double yaw_rad, AlignSource source, double sigma_deg) {
  if (s < 0 || s >= kSegmentCount || !seg_[s].aligned || !std::isfinite(yaw_rad)) return;
  SegmentAlignment& a = seg_[s];
  calib_.q_correction[s] = yaw_rotation(yaw_rad) * calib_.q_correction[s];
  calib_.q_sensor_segment[s] =
      turned_mounting(calib_.q_sensor_segment[s], pose_orientation(s), yaw_rad);
  a.heading_rad = wrap_angle_rad(a.heading_rad + yaw_rad);
  a.heading_source = source;
  a.heading_sigma_deg = sigma_deg;
  if (a.facing.known()) a.facing.yaw_rad = wrap_angle_rad(a.facing.yaw_rad - yaw_rad);
  changed(s);
}

void Alignment::turn_mounting(int s, double yaw_rad, AlignSource source) {
  if (s < 0 || s >= kSegmentCount || !seg_[s].aligned || !std::isfinite(yaw_rad)) return;
  calib_.q_sensor_segment[s] =
      turned_mounting(calib_.q_sensor_segment[s], pose_orientation(s), yaw_rad);
  seg_[s].facing.source = source;
  changed(s);
}

void Alignment::reset_heading(const std::array<Eigen::Quaterniond, kSegmentCount>& q_es,
                              const std::array<bool, kSegmentCount>& have,
                              const double* target_heading_rad) {
  std::array<double, kSegmentCount> yaw{};
  double sx = 0, sy = 0;
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!have[i]) continue;
    yaw[i] = yaw_of_rad(calib_.segment_from_sensor(i, q_es[i]));
    sx += std::cos(yaw[i]);
    sy += std::sin(yaw[i]);
  }
  if (!target_heading_rad && !have[0] && std::hypot(sx, sy) < 1e-9) return;
  const double ref = target_heading_rad ? *target_heading_rad
                     : have[0]          ? yaw[0]
                                        : std::atan2(sy, sx);
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!have[i]) continue;
    calib_.q_correction[i] = (yaw_rotation(ref - yaw[i]) * calib_.q_correction[i]).normalized();
    seg_[i].heading_rad = wrap_angle_rad(seg_[i].heading_rad + ref - yaw[i]);
    seg_[i].heading_source = AlignSource::heading_reset;
  }
  ++revision_;
}

}  // namespace mocap::rig
