// A BVH file as virtual-performer motion: an optional prelude (the calibration procedure), the
// N-pose lead-in for calibration, a blend into the clip, Catmull-Rom interpolation between
// frames (see make_bvh_motion in motion.hpp).
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
                std::shared_ptr<const Motion> prelude)
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
  double duration_s() const override {
    return prelude_s_ + lead_s_ + blend_s_ + (static_cast<double>(q_.size()) - 1) * frame_s_;
  }
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
        q[s] = q_stand_.slerp(w, q_[0][s]);
      p = (1 - w) * p_stand_ + w * p_[0];
    } else {
      const double x =
          std::min((t_s - lead_s_ - blend_s_) / frame_s_, static_cast<double>(q_.size()) - 1);
      const int n = static_cast<int>(q_.size());
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
    out.q_earth_pelvis = q[0];
    out.p_earth_pelvis_m = p;
    for (int s = 1; s < kSegmentCount; ++s)
      out.q_parent_segment[s] = q[kSegmentParent[s]].conjugate() * q[s];
  }

 private:
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
  BodyDimensions dims_;
  std::vector<std::array<Eigen::Quaterniond, kSegmentCount>> q_;
  std::vector<Eigen::Vector3d> p_;
  Eigen::Quaterniond q_stand_;
  Eigen::Vector3d p_stand_;
};

}  // namespace

std::unique_ptr<Motion> make_bvh_motion(const std::string& path, double lead_in_s, double blend_s,
                                        std::shared_ptr<const Motion> prelude) {
  return std::make_unique<BvhFileMotion>(BvhMotion(load_bvh(path)), lead_in_s, blend_s,
                                         std::move(prelude));
}

}  // namespace mocap::sim
