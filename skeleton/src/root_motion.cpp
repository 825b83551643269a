// Stance-foot root motion.
#include "mocap/skeleton/root_motion.hpp"

namespace mocap {

RootMotion::RootMotion(const BodyModel& model, RootMotionOptions options)
    : opt_(options), pelvis_height_m_(model.pelvis_height_m()) {
  const Eigen::Vector3d end = model.end_offset_m(index(Segment::foot_l));
  heel_local_ = Eigen::Vector3d(0, 0, end.z());
  toe_local_ = options.ankle_contact ? heel_local_ : end;
  reset();
}

void RootMotion::reset(const Eigen::Vector3d& p_m) {
  anchored_ = false;
  have_prev_ = false;
  root_m_ = Eigen::Vector3d(p_m.x(), p_m.y(), pelvis_height_m_);
}

Eigen::Vector3d RootMotion::update(const std::array<Eigen::Vector3d, kSegmentCount>& p_rel,
                                   const std::array<Eigen::Quaterniond, kSegmentCount>& q,
                                   double dt_s) {
  if (opt_.pinned) {
    Eigen::Vector3d p = opt_.pinned_position_m;
    if (p.z() < 0) p.z() = pelvis_height_m_;
    root_m_ = p;
    return p;
  }
  const int feet[2] = {index(Segment::foot_l), index(Segment::foot_r)};
  Eigen::Vector3d pt[2][2];
  double low[2];
  for (int f = 0; f < 2; ++f) {
    const int s = feet[f];
    pt[f][0] = p_rel[s] + q[s] * heel_local_;
    pt[f][1] = p_rel[s] + q[s] * toe_local_;
    low[f] = std::min(pt[f][0].z(), pt[f][1].z());
  }
  const double zmin = std::min(low[0], low[1]);
  const double root_z = opt_.floor_contact ? -zmin : pelvis_height_m_;

  int cur = stance_foot_ == feet[0] ? 0 : 1;
  if (!anchored_) {
    cur = low[0] <= low[1] ? 0 : 1;
    anchor_point_ = pt[cur][0].z() <= pt[cur][1].z() ? 0 : 1;
    anchor_xy_ = root_m_.head<2>() + pt[cur][anchor_point_].head<2>();
    anchored_ = true;
  }
  // Root from the current anchor.
  Eigen::Vector2d root_xy = anchor_xy_ - pt[cur][anchor_point_].head<2>();
  // Stance switch (other foot clearly lower) or contact-point switch within the stance foot.
  const int other = 1 - cur;
  int new_foot = cur;
  if (low[other] < low[cur] - opt_.stance_hysteresis_m) new_foot = other;
  const double gap = low[cur] - low[other];
  if (opt_.lift_rate_m_s > 0 && dt_s > 0 && have_prev_ && gap > opt_.lift_gap_m &&
      gap - prev_gap_m_ > opt_.lift_rate_m_s * dt_s)
    new_foot = other;
  const int new_point = pt[new_foot][0].z() <= pt[new_foot][1].z() ? 0 : 1;
  if (new_foot != cur || new_point != anchor_point_) {
    if (new_foot != cur ||
        std::abs(pt[cur][0].z() - pt[cur][1].z()) > 0.5 * opt_.stance_hysteresis_m) {
      cur = new_foot;
      anchor_point_ = new_point;
      anchor_xy_ = root_xy + pt[cur][anchor_point_].head<2>();
    }
  }
  prev_gap_m_ = low[cur] - low[1 - cur];
  have_prev_ = true;
  stance_foot_ = feet[cur];
  root_m_ = Eigen::Vector3d(root_xy.x(), root_xy.y(), root_z);
  return root_m_;
}

}  // namespace mocap
