// PoseCapturer: the still-pose capture's running sums and its verdict (see pose_capture.hpp).
#include "mocap/rig/pose_capture.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "mocap/core/units.hpp"

namespace mocap::rig {

PoseCapturer::PoseCapturer(RigMapping rig, PoseCaptureOptions options) : rig_(rig), opt_(options) {}

void PoseCapturer::start(CalibrationPose pose, int64_t t_start_ns) {
  pose_ = pose;
  capturing_ = true;
  t_start_ns_ = t_start_ns;
  t_last_ns_ = t_start_ns;
  acc_.fill(Accum{});
}

double PoseCapturer::progress(int64_t t_ns) const {
  if (!capturing_) return 0;
  const double p = static_cast<double>(t_ns - t_start_ns_) * 1e-9 / opt_.capture_s;
  return std::clamp(p, 0.0, 1.0);
}

void PoseCapturer::add_sample(int segment, const Eigen::Quaterniond& q, int64_t t_ns,
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
    a.acc_norm_max_dev = std::max(a.acc_norm_max_dev, std::abs(f.norm() - kStandardGravity_m_s2));
    ++a.n_acc;
  }
  t_last_ns_ = std::max(t_last_ns_, t_ns);
}

PoseCapturer::Result PoseCapturer::finish() {
  Result r;
  capturing_ = false;
  PoseCapture& c = r.capture;
  c.pose = pose_;
  c.t_end_ns = t_last_ns_;
  std::ostringstream msg;
  const int min_samples =
      std::max(1, static_cast<int>(opt_.min_sample_fraction * opt_.capture_s * 10.0));
  bool samples_short = false, moved = false, tilted = false;
  for (int i = 0; i < kSegmentCount; ++i) {
    c.gravity_error_deg[i] = -1;
    if (!rig_.tracked(i)) continue;
    c.have[i] = true;
    const Accum& a = acc_[i];
    const std::string_view seg = name(static_cast<Segment>(i));
    c.samples[i] = a.n;
    if (a.n < min_samples) {
      msg << seg << ": only " << a.n << " samples (need " << min_samples << "); ";
      samples_short = true;
      continue;
    }
    // The mean orientation is the principal eigenvector of sum(q q^T); its eigenvalue gives the
    // spread.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(a.qq);
    const Eigen::Vector4d v = es.eigenvectors().col(3);
    c.q_earth_sensor[i] = Eigen::Quaterniond(v[3], v[0], v[1], v[2]).normalized();
    const double lam = std::clamp(es.eigenvalues()[3] / a.n, 0.0, 1.0);
    c.motion_deg[i] = 2.0 * std::acos(std::sqrt(lam)) * kDegPerRad;
    c.worst_motion_deg = std::max(c.worst_motion_deg, c.motion_deg[i]);
    if (c.motion_deg[i] > opt_.max_motion_deg) {
      msg << seg << ": moved " << c.motion_deg[i] << " deg RMS (max " << opt_.max_motion_deg
          << "); ";
      moved = true;
    }
    if (a.n_acc == 0) continue;
    const Eigen::Vector3d f = a.acc_earth / a.n_acc;
    const double tilt =
        std::acos(std::clamp(f.z() / std::max(f.norm(), 1e-9), -1.0, 1.0)) * kDegPerRad;
    c.gravity_error_deg[i] = tilt;
    c.worst_gravity_error_deg = std::max(c.worst_gravity_error_deg, tilt);
    if (tilt > opt_.max_gravity_error_deg) {
      msg << seg << ": attitude disagrees with gravity by " << tilt << " deg (max "
          << opt_.max_gravity_error_deg << "); ";
      tilted = true;
    }
    if (a.acc_norm_max_dev > opt_.max_acc_norm_error_m_s2) {
      msg << seg << ": accelerating (|acc| off g by " << a.acc_norm_max_dev << " m/s^2); ";
      moved = true;
    }
  }
  r.ok = !(samples_short || moved || tilted);
  if (r.ok) return r;
  // Say what to do differently, once per kind of problem.
  std::string todo;
  if (samples_short)
    todo += " Check that every sensor streams (mocapctl status) before calibrating.";
  if (moved) {
    char s[16];
    std::snprintf(s, sizeof s, "%.1f", opt_.capture_s);
    todo += std::string(" Stand still for the whole capture (") + s +
            " s after the countdown); the pose need not be exact.";
  }
  if (tilted)
    todo += " Let the sensors lie still for a few seconds after switching them on, then try again.";
  r.message = "calibration refused: " + msg.str() + "-" + todo;
  return r;
}

}  // namespace mocap::rig
