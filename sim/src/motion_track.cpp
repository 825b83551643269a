// MotionTrack: pelvis translation from foot contact, integrated once at construction, and looping.
// The weight-bearing foot is given by the motion (gait phase) or else is the lower ankle (blended
// over 1 cm of height difference with a C2 smoothstep). Pelvis height puts the weighted ankles on
// the floor; horizontal pelvis velocity is minus the weighted velocity of the ankles relative to
// the pelvis, so a planted ankle does not slide. Horizontal position is that velocity integrated on
// a 5 ms grid (3-point Gauss-Legendre), exact to ~1e-12 m, so the simulator can differentiate
// positions numerically for accelerometers.
#include <cmath>
#include <stdexcept>

#include "mocap/sim/motion.hpp"
#include "smoothstep.hpp"

namespace mocap::sim {
namespace {

constexpr double kBlendHeightM = 0.01;

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

// Gauss-Legendre 3-point nodes and weights on [0, 1].
constexpr double kGaussNode[3] = {0.5 - 0.3872983346207417, 0.5, 0.5 + 0.3872983346207417};
constexpr double kGaussWeight[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};

}  // namespace

MotionTrack::MotionTrack(std::shared_ptr<const Motion> motion, const BodyDimensions& dims,
                         bool loop)
    : motion_(std::move(motion)), dims_(dims), loop_(loop) {
  if (!motion_ || !(motion_->duration_s() > 0))
    throw std::invalid_argument("MotionTrack: motion is empty (duration must be > 0)");
  const auto ref = reference_joint_positions(dims_);
  ankle_height_m_ = ref[index(Segment::foot_l)].z();
  if (motion_->has_root_translation()) return;
  const int n = static_cast<int>(std::ceil(period_s() / grid_s_)) + 1;
  root_xy_.resize(n + 1);
  root_xy_[0].setZero();
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (int g = 0; g < 3; ++g)
      step += kGaussWeight[g] * root_velocity((k + kGaussNode[g]) * grid_s_);
    root_xy_[k + 1] = root_xy_[k] + step * grid_s_;
  }
  BodyPose start, end;
  local_pose(0, start);
  local_pose(period_s(), end);
  loop_yaw_rad_ = yaw_of(end.q_earth_pelvis) - yaw_of(start.q_earth_pelvis);
  loop_shift_m_ = end.p_earth_pelvis_m - start.p_earth_pelvis_m;
  loop_shift_m_.z() = 0;
}

void MotionTrack::contacts(const BodyPose& o, Contacts& c) const {
  // Heel (below the ankle, on the floor in the N-pose) and toe (the foot's end point) of each
  // foot relative to the pelvis origin, earth axes (leg chains only).
  auto foot_points = [&](Segment thigh, Segment shank, Segment foot, Eigen::Vector3d* out) {
    const Eigen::Quaterniond q_thigh = o.q_earth_pelvis * o.q_parent_segment[index(thigh)];
    const Eigen::Quaterniond q_shank = q_thigh * o.q_parent_segment[index(shank)];
    const Eigen::Quaterniond q_foot = q_shank * o.q_parent_segment[index(foot)];
    const Eigen::Vector3d ankle = o.q_earth_pelvis * dims_.joint_offset_m[index(thigh)] +
                                  q_thigh * dims_.joint_offset_m[index(shank)] +
                                  q_shank * dims_.joint_offset_m[index(foot)];
    out[0] = ankle + q_foot * Eigen::Vector3d(0, 0, -ankle_height_m_);
    out[1] = ankle + q_foot * dims_.end_offset_m[index(foot)];
  };
  foot_points(Segment::thigh_l, Segment::shank_l, Segment::foot_l, &c.p[0]);
  foot_points(Segment::thigh_r, Segment::shank_r, Segment::foot_r, &c.p[2]);
  // Within a foot the lower of heel and toe carries it; between feet the lower foot. Both
  // blended over kBlendHeightM of height difference (C2).
  auto blend = [](double z_a, double z_b) {  // weight of b
    return smoothstep5((z_a - z_b + kBlendHeightM) / (2 * kBlendHeightM));
  };
  const double toe_l = blend(c.p[0].z(), c.p[1].z()), toe_r = blend(c.p[2].z(), c.p[3].z());
  const double z_l = (1 - toe_l) * c.p[0].z() + toe_l * c.p[1].z();
  const double z_r = (1 - toe_r) * c.p[2].z() + toe_r * c.p[3].z();
  const double w_r = blend(z_l, z_r);
  c.w[0] = (1 - w_r) * (1 - toe_l);
  c.w[1] = (1 - w_r) * toe_l;
  c.w[2] = w_r * (1 - toe_r);
  c.w[3] = w_r * toe_r;
  c.z_m = -((1 - w_r) * z_l + w_r * z_r);  // floor at z = 0
}

Eigen::Vector3d MotionTrack::root_velocity(double t_s) const {
  // Minus the weighted velocity of the contact points relative to the pelvis: velocities are
  // blended, not positions, so rolling from heel to toe does not drag the foot along its sole.
  const double h = 1e-5;
  BodyPose a, b;
  motion_->pose(t_s - h, a);
  motion_->pose(t_s + h, b);
  Contacts ca, cb;
  contacts(a, ca);
  contacts(b, cb);
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int i = 0; i < 4; ++i)
    v -= 0.5 * (ca.w[i] + cb.w[i]) * (cb.p[i] - ca.p[i]) / (2 * h);
  v.z() = 0;
  return v;
}

void MotionTrack::local_pose(double t_s, BodyPose& out) const {
  t_s = std::clamp(t_s, 0.0, period_s());
  motion_->pose(t_s, out);
  if (motion_->has_root_translation()) return;
  Contacts c;
  contacts(out, c);
  const double x = t_s / grid_s_;
  const int k = std::min(static_cast<int>(x), static_cast<int>(root_xy_.size()) - 2);
  const double dt = t_s - k * grid_s_;
  Eigen::Vector3d p = root_xy_[k];
  if (dt > 0) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (int g = 0; g < 3; ++g)
      step += kGaussWeight[g] * root_velocity(k * grid_s_ + kGaussNode[g] * dt);
    p += step * dt;
  }
  p.z() = c.z_m;
  out.p_earth_pelvis_m = p;
}

void MotionTrack::pose(double t_s, BodyPose& out) const {
  if (t_s < 0) t_s = 0;
  if (!loop_ || t_s <= period_s()) return local_pose(t_s, out);
  const long n = static_cast<long>(std::floor(t_s / period_s()));
  local_pose(t_s - n * period_s(), out);
  // Each loop starts where the previous ended: rotate by the accumulated heading, shift by the
  // accumulated displacements.
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  for (long j = 0; j < n; ++j)
    shift += Eigen::AngleAxisd(j * loop_yaw_rad_, Eigen::Vector3d::UnitZ()) * loop_shift_m_;
  const Eigen::Quaterniond q_yaw(Eigen::AngleAxisd(n * loop_yaw_rad_, Eigen::Vector3d::UnitZ()));
  out.q_earth_pelvis = q_yaw * out.q_earth_pelvis;
  const double z = out.p_earth_pelvis_m.z();
  out.p_earth_pelvis_m = shift + q_yaw * out.p_earth_pelvis_m;
  out.p_earth_pelvis_m.z() = z;
}

}  // namespace mocap::sim
