// Calibration capture and evaluation (N-pose, T-pose, N-then-T arm swing), heading reset.
#include "mocap/skeleton/calibration.hpp"
#include "mocap/core/units.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {

bool is_arm(int s) {
  return s == index(Segment::upper_arm_l) || s == index(Segment::forearm_l) ||
         s == index(Segment::hand_l) || s == index(Segment::upper_arm_r) ||
         s == index(Segment::forearm_r) || s == index(Segment::hand_r);
}
bool is_left_arm(int s) {
  return s == index(Segment::upper_arm_l) || s == index(Segment::forearm_l) ||
         s == index(Segment::hand_l);
}

Eigen::Quaterniond to_quat(const Eigen::Vector4d& xyzw) {
  return Eigen::Quaterniond(xyzw[3], xyzw[0], xyzw[1], xyzw[2]).normalized();
}
}  // namespace

std::string_view to_string(CalibrationPose p) {
  return p == CalibrationPose::npose ? "npose" : "tpose";
}

std::string_view to_string(HeadingSource h) {
  switch (h) {
    case HeadingSource::pelvis_sensor:
      return "pelvis_sensor";
    case HeadingSource::mean_sensors:
      return "mean_sensors";
    case HeadingSource::explicit_heading:
      return "explicit_heading";
    case HeadingSource::arm_swing:
      return "arm_swing";
    case HeadingSource::mount_normals:
      return "mount_normals";
  }
  return "?";
}

Eigen::Quaterniond q_body_segment_in_pose(CalibrationPose pose, int segment) {
  if (pose == CalibrationPose::tpose && is_arm(segment))
    return axis_rotation(0, is_left_arm(segment) ? M_PI / 2 : -M_PI / 2);
  return Eigen::Quaterniond::Identity();
}

Calibrator::Calibrator(RigMapping rig, CalibratorOptions options) : rig_(rig), opt_(options) {
  npose_mean_.fill(Eigen::Quaterniond::Identity());
}

void Calibrator::start(CalibrationPose pose, int64_t t_start_ns) {
  pose_ = pose;
  capturing_ = true;
  t_start_ns_ = t_start_ns;
  t_last_ns_ = t_start_ns;
  acc_.fill(Accum{});
}

double Calibrator::progress(int64_t t_ns) const {
  if (!capturing_) return 0;
  const double p = static_cast<double>(t_ns - t_start_ns_) * 1e-9 / opt_.capture_s;
  return p < 0 ? 0 : (p > 1 ? 1 : p);
}

void Calibrator::add_sample(int segment, const Eigen::Quaterniond& q, int64_t t_ns,
                            const Eigen::Vector3d* acc_sensor_m_s2) {
  if (!capturing_ || segment < 0 || segment >= kSegmentCount || t_ns < t_start_ns_) return;
  if (!q.coeffs().allFinite() || q.norm() < 0.5) return;
  const Eigen::Quaterniond qn = q.normalized();
  Accum& a = acc_[segment];
  const Eigen::Vector4d c = qn.coeffs();
  a.qq.noalias() += c * c.transpose();
  ++a.n;
  if (acc_sensor_m_s2 && acc_sensor_m_s2->allFinite()) {
    const Eigen::Vector3d f = qn * *acc_sensor_m_s2;
    a.acc_earth += f;
    const double dev = std::abs(f.norm() - kStandardGravity_m_s2);
    a.acc_norm_max_dev = std::max(a.acc_norm_max_dev, dev);
    ++a.n_acc;
  }
  if (t_ns > t_last_ns_) t_last_ns_ = t_ns;
}

CalibrationResult Calibrator::finish() {
  CalibrationResult r;
  capturing_ = false;
  std::ostringstream msg;
  std::array<Eigen::Quaterniond, kSegmentCount> mean;
  mean.fill(Eigen::Quaterniond::Identity());
  const int min_samples =
      std::max(1, static_cast<int>(opt_.min_sample_fraction * opt_.capture_s * 10.0));
  bool refused = false;
  double worst_motion = 0, worst_grav = 0;
  for (int i = 0; i < kSegmentCount; ++i) {
    r.gravity_error_deg[i] = -1;
    if (!rig_.tracked(i)) continue;
    const Accum& a = acc_[i];
    r.samples[i] = a.n;
    if (a.n < min_samples) {
      msg << name(static_cast<Segment>(i)) << ": only " << a.n << " samples (need " << min_samples
          << "); ";
      refused = true;
      continue;
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(a.qq);
    const Eigen::Vector4d v = es.eigenvectors().col(3);
    const double lam = std::clamp(es.eigenvalues()[3] / a.n, 0.0, 1.0);
    mean[i] = to_quat(v);
    r.motion_deg[i] = 2.0 * std::acos(std::sqrt(lam)) * kDegPerRad;
    worst_motion = std::max(worst_motion, r.motion_deg[i]);
    if (r.motion_deg[i] > opt_.max_motion_deg) {
      msg << name(static_cast<Segment>(i)) << ": moved " << r.motion_deg[i] << " deg RMS (max "
          << opt_.max_motion_deg << "); ";
      refused = true;
    }
    if (a.n_acc > 0) {
      const Eigen::Vector3d f = a.acc_earth / a.n_acc;
      const double tilt =
          std::acos(std::clamp(f.z() / std::max(f.norm(), 1e-9), -1.0, 1.0)) * kDegPerRad;
      r.gravity_error_deg[i] = tilt;
      worst_grav = std::max(worst_grav, tilt);
      if (tilt > opt_.max_gravity_error_deg) {
        msg << name(static_cast<Segment>(i)) << ": attitude disagrees with gravity by " << tilt
            << " deg (max " << opt_.max_gravity_error_deg << "); ";
        refused = true;
      }
      if (a.acc_norm_max_dev > opt_.max_acc_norm_error_m_s2) {
        msg << name(static_cast<Segment>(i)) << ": accelerating (|acc| off g by "
            << a.acc_norm_max_dev << " m/s^2); ";
        refused = true;
      }
    }
  }
  if (refused) {
    // Say what to do differently, once per kind of problem.
    const std::string found = msg.str();
    std::string todo;
    if (found.find("samples (need") != std::string::npos)
      todo += " Check that every sensor streams (mocapctl status) before calibrating.";
    if (found.find("moved") != std::string::npos || found.find("accelerating") != std::string::npos)
      todo += " Stand still for the whole capture (" + std::to_string(opt_.capture_s).substr(0, 4) +
              " s after the countdown); the pose need not be exact.";
    if (found.find("gravity") != std::string::npos)
      todo +=
          " Let the sensors lie still for a few seconds after switching them on, then try "
          "again.";
    r.message = "calibration refused: " + found + "-" + todo;
    return r;
  }

  // How far the person stood from the assumed pose, where a site normal shows it (its tilt).
  std::array<double, kSegmentCount>& dev = r.pose_deviation_deg;
  int worst_dev = -1;
  for (int i = 0; i < kSegmentCount; ++i) {
    dev[i] = -1;
    const Eigen::Vector3d& n_body = opt_.mount_normal_body[i];
    if (!rig_.tracked(i) || n_body.squaredNorm() == 0) continue;
    const Eigen::Vector3d n_pose = q_body_segment_in_pose(pose_, i) * n_body.normalized();
    const Eigen::Vector3d n_earth = mean[i] * opt_.heading_axis_sensor.normalized();
    dev[i] = std::abs(std::asin(std::clamp(n_earth.z(), -1.0, 1.0)) -
                      std::asin(std::clamp(n_pose.z(), -1.0, 1.0))) *
             kDegPerRad;
    if (worst_dev < 0 || dev[i] > dev[worst_dev]) worst_dev = i;
  }
  bool independent_unaligned = false;
  std::ostringstream local_field;  // sensors whose heading a local field had turned

  // Heading of the body.
  double heading_rad = 0;
  auto forward_heading = [&](const Eigen::Quaterniond& m, double& out) {
    const Eigen::Vector3d f = m * opt_.heading_axis_sensor.normalized();
    if (std::hypot(f.x(), f.y()) < 0.3) return false;
    out = std::atan2(f.y(), f.x());
    return true;
  };
  switch (opt_.heading) {
    case HeadingSource::pelvis_sensor:
      if (!rig_.tracked(0) || !forward_heading(mean[0], heading_rad)) {
        r.message = rig_.tracked(0)
                        ? "calibration refused: pelvis sensor's heading axis is near vertical"
                        : "calibration refused: heading from the pelvis needs a pelvis sensor";
        return r;
      }
      break;
    case HeadingSource::mean_sensors: {
      double sx = 0, sy = 0;
      for (int i = 0; i < kSegmentCount; ++i) {
        double h;
        if (rig_.tracked(i) && forward_heading(mean[i], h)) {
          sx += std::cos(h);
          sy += std::sin(h);
        }
      }
      if (std::hypot(sx, sy) < 1e-6) {
        r.message = "calibration refused: no sensor with a horizontal heading axis";
        return r;
      }
      heading_rad = std::atan2(sy, sx);
      break;
    }
    case HeadingSource::explicit_heading:
      heading_rad = opt_.explicit_heading_deg * kRadPerDeg;
      break;
    case HeadingSource::mount_normals: {
      // Each horizontal normal gives one heading (weighted alike; near-vertical sites such as
      // the head and feet do not count). Circular mean, then again over the sensors within
      // kMaxNormalSpreadDeg of it: a sensor whose filter took a local field as north (a magnet
      // near it) is off by far more than a strap's misalignment and must not pull the body.
      constexpr double kMaxNormalSpreadDeg = 12.0;
      std::array<double, kSegmentCount> h_site{};
      std::array<bool, kSegmentCount> use{};
      for (int i = 0; i < kSegmentCount; ++i) {
        const Eigen::Vector3d& n_body = opt_.mount_normal_body[i];
        const bool horizontal =
            std::hypot(n_body.x(), n_body.y()) >= 0.5 * n_body.norm() && n_body.norm() > 0;
        use[i] = rig_.tracked(i) && horizontal && forward_heading(mean[i], h_site[i]);
        if (use[i]) h_site[i] -= std::atan2(n_body.y(), n_body.x());
      }
      const auto circular_mean = [&](double center_rad, double max_dev_rad, int& used) {
        double sx = 0, sy = 0;
        used = 0;
        for (int i = 0; i < kSegmentCount; ++i) {
          if (!use[i] || std::abs(std::remainder(h_site[i] - center_rad, 2 * M_PI)) > max_dev_rad)
            continue;
          sx += std::cos(h_site[i]);
          sy += std::sin(h_site[i]);
          ++used;
        }
        return std::atan2(sy, sx);
      };
      // Sensors with a heading frame of their own do not vote on the body heading.
      std::array<bool, kSegmentCount> own_frame_use{};
      bool any_own = false;
      for (int i = 0; i < kSegmentCount; ++i) {
        const bool own = opt_.own_heading_frame[i] && rig_.tracked(i);
        any_own = any_own || own;
        own_frame_use[i] = own && use[i];
        if (own) use[i] = false;
      }
      int used = 0;
      if (any_own) {
        bool any_shared = false;
        for (int i = 0; i < kSegmentCount; ++i)
          any_shared = any_shared || use[i];
        heading_rad = 0;
        if (any_shared) {
          heading_rad = circular_mean(0, 4 * M_PI, used);
          heading_rad = circular_mean(heading_rad, kMaxNormalSpreadDeg * kRadPerDeg, used);
        }
        // Each own-frame sensor aligned on its own normal onto that body heading.
        int aligned = 0;
        for (int i = 0; i < kSegmentCount; ++i) {
          if (!opt_.own_heading_frame[i] || !rig_.tracked(i)) continue;
          int from = i;
          while (from >= 0 && !own_frame_use[from])
            from = kSegmentParent[from];
          r.heading_from_own_normal[i] = from == i;
          if (from < 0) continue;
          r.calibration.q_correction[i] = yaw_rotation(heading_rad - h_site[from]);
          aligned += from == i;
        }
        if (aligned == 0) independent_unaligned = true;
        break;
      }
      heading_rad = circular_mean(0, 4 * M_PI, used);
      if (used > 0)
        heading_rad = circular_mean(heading_rad, kMaxNormalSpreadDeg * kRadPerDeg, used);
      if (used == 0) {
        r.message =
            "calibration refused: no sensor with a known horizontal mount normal agrees on the "
            "heading";
        return r;
      }
      // A sensor off by far more than a strap's tilt may have taken a local field for north
      // (or the person's pose is turned there, e.g. feet turned out): reported, for its filter
      // to watch whether the field changes by as much once the sensor moves.
      for (int i = 0; i < kSegmentCount; ++i) {
        if (!use[i]) continue;
        const double off = std::remainder(h_site[i] - heading_rad, 2 * M_PI);
        if (std::abs(off) <= CalibrationResult::kLocalFieldDeg * kRadPerDeg) continue;
        r.heading_off_normal_rad[i] = off;
        local_field << (local_field.tellp() > 0 ? ", " : "") << name(static_cast<Segment>(i)) << " "
                    << std::lround(off * kDegPerRad) << " deg";
      }
      break;
    }
    case HeadingSource::arm_swing: {
      if (pose_ == CalibrationPose::npose) {
        npose_mean_ = mean;
        have_npose_ = true;
        r.status = CalibrationStatus::need_tpose;
        r.message = "N-pose captured; now hold the T-pose";
        return r;
      }
      if (!have_npose_) {
        r.message = "calibration refused: arm_swing needs an N-pose capture before the T-pose";
        return r;
      }
      Eigen::Vector3d axis = Eigen::Vector3d::Zero();
      int used = 0;
      for (int s : {index(Segment::upper_arm_l), index(Segment::upper_arm_r)}) {
        if (!rig_.tracked(s)) continue;
        const Eigen::AngleAxisd d(mean[s] * npose_mean_[s].conjugate());
        const double ang_deg = d.angle() * kDegPerRad;
        if (ang_deg < 60 || ang_deg > 120) {
          r.message = "calibration refused: " + std::string(name(static_cast<Segment>(s))) +
                      " rose " + std::to_string(ang_deg) +
                      " deg between N- and T-pose (expect ~90)";
          return r;
        }
        axis += (is_left_arm(s) ? 1.0 : -1.0) * d.axis();
        ++used;
      }
      if (used == 0 || std::hypot(axis.x(), axis.y()) < 0.3 * used) {
        r.message =
            "calibration refused: arm_swing needs an upper-arm sensor rotating about a "
            "horizontal axis";
        return r;
      }
      heading_rad = std::atan2(axis.y(), axis.x());
      have_npose_ = false;
      break;
    }
  }

  Calibration& c = r.calibration;
  c.valid = true;
  c.pose = pose_;
  c.heading_source = opt_.heading;
  c.heading_deg = heading_rad * kDegPerRad;
  c.motion_deg = worst_motion;
  c.gravity_error_deg = worst_grav;
  const Eigen::Quaterniond q_earth_body = yaw_rotation(heading_rad);
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!rig_.tracked(i)) continue;
    c.calibrated[i] = true;
    const Eigen::Quaterniond q_earth_sensor = c.q_correction[i] * mean[i];
    c.q_sensor_segment[i] =
        (q_earth_sensor.conjugate() * q_earth_body * q_body_segment_in_pose(pose_, i)).normalized();
  }
  r.status = CalibrationStatus::ok;
  std::ostringstream ok;
  ok.precision(3);
  ok << "calibrated in " << to_string(pose_) << ", heading " << c.heading_deg
     << " deg, worst motion " << worst_motion << " deg";
  if (worst_dev >= 0)
    ok << "; furthest from the " << to_string(pose_) << ": "
       << name(static_cast<Segment>(worst_dev)) << " tilted " << dev[worst_dev]
       << " deg (reported only: the tracked motion is unaffected)";
  if (local_field.tellp() > 0)
    ok << "; heading off the site normal (a magnet or steel near it, or the pose turned there): "
       << local_field.str() << " (corrected if the field turns by as much once it moves away)";
  if (independent_unaligned)
    ok << "; no sensor site with a horizontal normal: each 6D sensor keeps its own heading";
  r.message = ok.str();
  return r;
}

void apply_heading_reset(Calibration& c, const std::array<Eigen::Quaterniond, kSegmentCount>& q_es,
                         const std::array<bool, kSegmentCount>& have,
                         const double* target_heading_rad) {
  std::array<double, kSegmentCount> yaw{};
  double sx = 0, sy = 0;
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!have[i]) continue;
    yaw[i] = yaw_of_rad(c.segment_from_sensor(i, q_es[i]));
    sx += std::cos(yaw[i]);
    sy += std::sin(yaw[i]);
  }
  if (!target_heading_rad && !have[0] && std::hypot(sx, sy) < 1e-9) return;
  const double ref = target_heading_rad ? *target_heading_rad
                     : have[0]          ? yaw[0]
                                        : std::atan2(sy, sx);
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!have[i]) continue;
    c.q_correction[i] = (yaw_rotation(ref - yaw[i]) * c.q_correction[i]).normalized();
  }
}

}  // namespace mocap
