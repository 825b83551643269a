// A BVH file as virtual-performer motion: an optional prelude (the calibration procedure), the
// N-pose lead-in for calibration, a blend into the clip, Catmull-Rom interpolation between
// frames, the clip optionally played back and forth for a long session (see make_bvh_motion in
// motion.hpp).
#include <cmath>

#include "mocap/sim/motion.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "smoothstep.hpp"

namespace mocap::sim {
namespace {

template <class V>
V catmull_rom(const V& p0, const V& p1, const V& p2, const V& p3, double u) {
  const double u2 = u * u, u3 = u2 * u;
  return 0.5 * ((2 * p1) + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u2 +
                (-p0 + 3 * p1 - 3 * p2 + p3) * u3);
}

class BvhFileMotion final : public Motion {
 public:
  BvhFileMotion(BvhMotion bvh, double lead_in_s, double blend_s,
                std::shared_ptr<const Motion> prelude, double session_s)
      : prelude_(std::move(prelude)),
        prelude_s_(prelude_ ? prelude_->duration_s() : 0.0),
        lead_s_(lead_in_s),
        blend_s_(blend_s),
        dims_(bvh.dimensions()) {
    const int n = bvh.frames();
    if (n < 1) throw std::runtime_error("BVH file has no frames");
    frame_s_ = bvh.frame_time_s() > 0 ? bvh.frame_time_s() : 1.0 / 30;
    q_.resize(n);
    p_.resize(n);
    for (int k = 0; k < n; ++k) {
      bvh.frame(k, q_[k], p_[k]);
      for (int s = 0; s < kSegmentCount; ++s) {  // same hemisphere as the previous frame
        if (k > 0 && q_[k][s].dot(q_[k - 1][s]) < 0) q_[k][s].coeffs() *= -1;
      }
    }
    clip_s_ = (n - 1) * frame_s_;
    if (session_s > clip_s_ && clip_s_ > 0) {
      passes_ = static_cast<int>(std::ceil(session_s / clip_s_));
      turn_half_s_ = std::min(0.5, clip_s_ / 4);
    }
    // The blend's target: where the clip starts (a turning point when played back and forth).
    q_start_ = q_[0];
    p_start_ = p_[0];
    if (passes_ > 1) clip_at(clip_time_s(0), q_start_, p_start_);
    const Eigen::Vector3d x = q_[0][0] * Eigen::Vector3d::UnitX();
    q_stand_ = Eigen::AngleAxisd(std::atan2(x.y(), x.x()), Eigen::Vector3d::UnitZ());
    p_stand_ = p_[0];
    p_stand_.z() = dims_.joint_offset_m[0].z();
    if (prelude_) {
      BodyPose start;
      prelude_->pose(0.0, start);
      feet_stand_m_ = feet_from_pelvis(start);
    }
  }
  double duration_s() const override { return prelude_s_ + lead_s_ + blend_s_ + passes_ * clip_s_; }
  bool has_root_translation() const override { return true; }
  std::pair<double, double> calibration_window_s() const override {
    return prelude_ ? prelude_->calibration_window_s() : std::pair{0.0, lead_s_};
  }
  const BodyDimensions* dimensions() const override { return &dims_; }

  void pose(double t_s, BodyPose& out) const override {
    if (t_s < prelude_s_) {
      // The prelude facing the clip's first heading; the root moves so the feet stay planted.
      prelude_->pose(t_s, out);
      const Eigen::Vector3d feet_m = feet_from_pelvis(out);
      out.q_earth_pelvis = q_stand_ * out.q_earth_pelvis;
      out.p_earth_pelvis_m = p_stand_ + q_stand_ * (feet_stand_m_ - feet_m);
      return;
    }
    t_s -= prelude_s_;
    std::array<Eigen::Quaterniond, kSegmentCount> q;
    Eigen::Vector3d p;
    if (t_s < lead_s_ + blend_s_) {
      const double w = smoothstep5((t_s - lead_s_) / std::max(blend_s_, 1e-9));
      for (int s = 0; s < kSegmentCount; ++s)
        q[s] = q_stand_.slerp(w, q_start_[s]);
      p = (1 - w) * p_stand_ + w * p_start_;
    } else {
      clip_at(clip_time_s(t_s - lead_s_ - blend_s_), q, p);
    }
    out.q_earth_pelvis = q[0];
    out.p_earth_pelvis_m = p;
    for (int s = 1; s < kSegmentCount; ++s)
      out.q_parent_segment[s] = q[kSegmentParent[s]].conjugate() * q[s];
  }

 private:
  /// The clip's pose at clip time x_s, Catmull-Rom between its frames.
  void clip_at(double x_s, std::array<Eigen::Quaterniond, kSegmentCount>& q,
               Eigen::Vector3d& p) const {
    const int n = static_cast<int>(q_.size());
    const double x = std::clamp(x_s / frame_s_, 0.0, static_cast<double>(n) - 1);
    const int k = std::min(static_cast<int>(x), n - 1);
    const double u = x - k;
    auto at = [&](int i) { return std::clamp(i, 0, n - 1); };
    const int i0 = at(k - 1), i1 = at(k), i2 = at(k + 1), i3 = at(k + 2);
    p = catmull_rom(p_[i0], p_[i1], p_[i2], p_[i3], u);
    for (int s = 0; s < kSegmentCount; ++s) {
      const Eigen::Vector4d c = catmull_rom<Eigen::Vector4d>(
          q_[i0][s].coeffs(), q_[i1][s].coeffs(), q_[i2][s].coeffs(), q_[i3][s].coeffs(), u);
      q[s] = Eigen::Quaterniond(c).normalized();
    }
  }

  /// Clip time at s_s seconds after the blend. Played once: s_s. Back and forth: a triangle
  /// wave between the clip's ends, period 2 clip_s_, averaged over a window of 2 turn_half_s_
  /// so each turning point eases through zero speed (no step in any segment's rate; the
  /// performer walks the same path back, as a person pacing a room). Starts at a turning point.
  double clip_time_s(double s_s) const {
    if (passes_ == 1) return s_s;
    const double L = clip_s_, h = turn_half_s_;
    // The triangle wave's integral: L^2 per period, quadratic within one.
    const auto integral = [L](double s) {
      const double n = std::floor(s / (2 * L)), r = s - 2 * L * n;
      const double within = r <= L ? r * r / 2 : L * L / 2 + L * (r - L) - (r - L) * (r - L) / 2;
      return n * L * L + within;
    };
    return (integral(s_s + h) - integral(s_s - h)) / (2 * h);
  }

  /// Mean of the two ankles relative to the pelvis, in the prelude's own (unturned) frame.
  Eigen::Vector3d feet_from_pelvis(BodyPose pose) const {
    pose.p_earth_pelvis_m.setZero();
    TruthFrame f;
    truth_forward_kinematics(dims_, pose, f);
    return 0.5 * (f.p_earth_segment_m[index(Segment::foot_l)] +
                  f.p_earth_segment_m[index(Segment::foot_r)]);
  }

  std::shared_ptr<const Motion> prelude_;
  double prelude_s_;
  Eigen::Vector3d feet_stand_m_ = Eigen::Vector3d::Zero();
  double lead_s_, blend_s_, frame_s_ = 1.0 / 30;
  double clip_s_ = 0;       // the clip's length, first to last frame
  int passes_ = 1;          // played once, or this many times back and forth
  double turn_half_s_ = 0;  // half the easing window at each turning point
  std::array<Eigen::Quaterniond, kSegmentCount> q_start_;
  Eigen::Vector3d p_start_ = Eigen::Vector3d::Zero();
  BodyDimensions dims_;
  std::vector<std::array<Eigen::Quaterniond, kSegmentCount>> q_;
  std::vector<Eigen::Vector3d> p_;
  Eigen::Quaterniond q_stand_;
  Eigen::Vector3d p_stand_;
};

}  // namespace

std::unique_ptr<Motion> make_bvh_motion(const std::string& path, double lead_in_s, double blend_s,
                                        std::shared_ptr<const Motion> prelude, double session_s) {
  return std::make_unique<BvhFileMotion>(BvhMotion(load_bvh(path)), lead_in_s, blend_s,
                                         std::move(prelude), session_s);
}

}  // namespace mocap::sim
