// Skeleton solver: calibrated orientations, inference of untracked segments, joint limits,
// forward kinematics, root motion, PoseFrame output.
#include "mocap/skeleton/skeleton.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

Skeleton::Skeleton(const BodyModel& model, const JointLimits& limits, RigMapping rig,
                   SkeletonOptions options)
    : model_(model), limits_(limits), rig_(rig), opt_(options), root_(model, options.root) {
  validate(limits_);
  q_es_.fill(Eigen::Quaterniond::Identity());
  q_ease_.fill(Eigen::Quaterniond::Identity());
  q_earth_.fill(Eigen::Quaterniond::Identity());
  q_joint_.fill(Eigen::Quaterniond::Identity());
  p_earth_.fill(Eigen::Vector3d::Zero());
  p_rel_.fill(Eigen::Vector3d::Zero());
  for (int i = 0; i < kSegmentCount; ++i) {
    chain_target_[i] = -1;
    int steps = 0;
    for (int c = kChainChild[i]; c >= 0; c = kChainChild[c]) {
      ++steps;
      if (rig_.tracked(c)) {
        chain_target_[i] = static_cast<int8_t>(c);
        chain_steps_[i] = static_cast<int8_t>(steps);
        break;
      }
    }
  }
}

void Skeleton::set_sensor_orientation(int segment, const Eigen::Quaterniond& q, int64_t t_ns,
                                      uint32_t sensor_flags) {
  if (segment < 0 || segment >= kSegmentCount || !rig_.tracked(segment)) {
    ++rejected_;
    return;
  }
  const double n = q.norm();
  if (!std::isfinite(n) || n < 0.5 || n > 2.0) {
    ++rejected_;
    return;
  }
  q_es_[segment] = Eigen::Quaterniond(q.coeffs() / n);
  t_in_ns_[segment] = t_ns;
  have_[segment] = true;
  in_flags_[segment] = sensor_flags & (kSegAtRest | kSegMagDisturbed | kSegMagNoReference);
  if (t_ns > t_newest_ns_) t_newest_ns_ = t_ns;
}

void Skeleton::set_calibration(const Calibration& c, bool ease) {
  for (int i = 0; i < kSegmentCount; ++i) {
    if (ease && calib_.valid && c.valid && calib_.calibrated[i] && c.calibrated[i])
      ease_segment(i, calib_.segment_from_sensor(i, q_es_[i]), c.segment_from_sensor(i, q_es_[i]));
    else
      q_ease_[i].setIdentity();
  }
  calib_ = c;
  ++calib_revision_;
}

void Skeleton::set_sensor_live(int segment, bool live) {
  if (segment >= 0 && segment < kSegmentCount) dead_[segment] = !live;
}

void Skeleton::ease_segment(int segment, const Eigen::Quaterniond& from,
                            const Eigen::Quaterniond& to) {
  if (segment < 0 || segment >= kSegmentCount || !have_[segment] || opt_.ease_deg_s <= 0) return;
  // Published before: ease from; after: ease' to. Continuous where ease' = ease from to^-1.
  const Eigen::Quaterniond e = q_ease_[segment] * from * to.conjugate();
  q_ease_[segment] = e.coeffs().allFinite() ? e.normalized() : Eigen::Quaterniond::Identity();
}

Eigen::Quaterniond Skeleton::ease_step(int i, double dt_s) {
  Eigen::Quaterniond& e = q_ease_[i];
  const double angle_rad = e.angularDistance(Eigen::Quaterniond::Identity());
  const double step_rad = opt_.ease_deg_s * kRadPerDeg * dt_s;
  if (!(angle_rad > step_rad)) {
    e.setIdentity();
  } else {
    e = Eigen::Quaterniond::Identity()
            .slerp(1.0 - step_rad / angle_rad, e)
            .normalized();  // short way
  }
  return e;
}

double Skeleton::drift_signal_deg() const {
  return *std::max_element(viol_avg_.begin(), viol_avg_.end());
}

void Skeleton::solve(PoseFrame& out) {
  solve(t_newest_ns_, out);
}

void Skeleton::solve(int64_t t_now_ns, PoseFrame& out) {
  std::array<uint32_t, kSegmentCount> flags{};
  std::array<bool, kSegmentCount> live{};
  const double dt_s =
      frame_ == 0 ? 0.0 : std::max(0.0, static_cast<double>(t_now_ns - t_prev_solve_ns_) * 1e-9);
  // 1. Segments with a sensor that has reported (an alignment change eased in).
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!rig_.tracked(i) || !have_[i] || dead_[i]) continue;
    live[i] = true;
    q_earth_[i] = calib_.segment_from_sensor(i, q_es_[i]);
    if (q_ease_[i].w() < 1.0) q_earth_[i] = (ease_step(i, dt_s) * q_earth_[i]).normalized();
    flags[i] = kSegTracked | in_flags_[i];
    if (t_now_ns - t_in_ns_[i] > opt_.stale_after_ns) flags[i] |= kSegStale;
  }
  // 2. Segments without (live) sensor, in depth-first order: slerp from the parent towards the
  //    tracked segment further down the chain, or copy the parent.
  for (int i = 0; i < kSegmentCount; ++i) {
    if (live[i]) continue;
    flags[i] = kSegInferred;
    const int p = kSegmentParent[i];
    int target = chain_target_[i];
    if (target >= 0 && !live[target]) target = -1;
    if (p < 0) {
      q_earth_[i] = target >= 0 ? q_earth_[target] : Eigen::Quaterniond::Identity();
    } else if (target >= 0) {
      q_earth_[i] = slerp_shortest(q_earth_[p], q_earth_[target], 1.0 / (chain_steps_[i] + 1));
    } else {
      q_earth_[i] = q_earth_[p];
    }
  }
  // 3. Joint rotations and their limits (reported, never imposed).
  const double alpha =
      opt_.violation_tau_s > 0 ? 1.0 - std::exp(-dt_s / opt_.violation_tau_s) : 1.0;
  for (int i = 0; i < kSegmentCount; ++i) {
    const int p = kSegmentParent[i];
    if (p < 0) {
      q_joint_[i] = q_earth_[i];
      checks_[i] = JointCheck{};
      continue;
    }
    q_joint_[i] = (q_earth_[p].conjugate() * q_earth_[i]).normalized();
    checks_[i] = check_joint(limits_.joint[i], q_joint_[i], nullptr);
    if (checks_[i].violated) flags[i] |= kSegLimitViolated;
    viol_avg_[i] += alpha * (checks_[i].violation_deg - viol_avg_[i]);
  }
  // 4. Forward kinematics with the pelvis at the origin (thesis Fig. 29).
  p_rel_[0].setZero();
  for (int i = 1; i < kSegmentCount; ++i) {
    const int p = kSegmentParent[i];
    p_rel_[i] = p_rel_[p] + q_earth_[p] * model_.joint_offset_m(i);
  }
  // 5. Root motion.
  const Eigen::Vector3d root = root_.update(p_rel_, q_earth_, dt_s);
  for (int i = 0; i < kSegmentCount; ++i)
    p_earth_[i] = p_rel_[i] + root;
  if (!opt_.root.pinned) flags[root_.stance_foot()] |= kSegStance;

  // 6. Publish.
  out.frame = frame_++;
  out.t_ns = t_now_ns;
  t_prev_solve_ns_ = t_now_ns;
  out.flags =
      calib_.valid ? (out.flags | kFrameCalibrated) : (out.flags & ~uint32_t{kFrameCalibrated});
  for (int i = 0; i < kSegmentCount; ++i) {
    out.q_earth_segment[i] = to_wxyz(q_earth_[i]);
    out.q_parent_segment[i] = to_wxyz(q_joint_[i]);
    out.p_earth_segment_m[i] = {static_cast<float>(p_earth_[i].x()),
                                static_cast<float>(p_earth_[i].y()),
                                static_cast<float>(p_earth_[i].z())};
    out.joint_violation_deg[i] = static_cast<float>(checks_[i].violation_deg);
    out.segment_flags[i] = flags[i];
  }
}

}  // namespace mocap
