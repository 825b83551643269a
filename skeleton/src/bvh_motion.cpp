// BVH clip -> our 16 segments: bone-name mapping, rest-pose alignment, dimensions, frames.
#include <cmath>
#include <stdexcept>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/forward_kinematics.hpp"
#include "mocap/skeleton/quat_math.hpp"
#include "mocap/skeleton/skeleton.hpp"

namespace mocap {

namespace {

// Accepted names per segment, first match wins (case-insensitive). Collars ("LeftShoulder" in
// CMU files) and extra spine joints are not segments: their rotations still propagate.
const std::array<std::vector<std::string_view>, kSegmentCount>& aliases() {
  static const std::array<std::vector<std::string_view>, kSegmentCount> a = {{
      {"Hips", "Hip", "Pelvis", "Root"},
      {"Spine", "Chest", "Abdomen", "Spine1", "Torso"},
      {"Neck", "Neck1"},
      {"Head"},
      {"LeftArm", "LeftUpArm", "lShldr", "LeftUpperArm", "L_UpperArm"},
      {"LeftForeArm", "LeftLowArm", "lForeArm", "LeftLowerArm", "L_Forearm"},
      {"LeftHand", "lHand", "L_Hand"},
      {"RightArm", "RightUpArm", "rShldr", "RightUpperArm", "R_UpperArm"},
      {"RightForeArm", "RightLowArm", "rForeArm", "RightLowerArm", "R_Forearm"},
      {"RightHand", "rHand", "R_Hand"},
      {"LeftUpLeg", "LeftHip", "lThigh", "LeftUpperLeg", "L_Thigh"},
      {"LeftLeg", "LeftLowLeg", "LeftKnee", "lShin", "LeftLowerLeg", "L_Calf"},
      {"LeftFoot", "LeftAnkle", "lFoot", "L_Foot"},
      {"RightUpLeg", "RightHip", "rThigh", "RightUpperLeg", "R_Thigh"},
      {"RightLeg", "RightLowLeg", "RightKnee", "rShin", "RightLowerLeg", "R_Calf"},
      {"RightFoot", "RightAnkle", "rFoot", "R_Foot"},
  }};
  return a;
}

}  // namespace

BvhMotion::BvhMotion(BvhClip clip, double m_per_unit)
    : clip_(std::move(clip)), m_per_unit_(m_per_unit) {
  if (!(m_per_unit_ > 0)) throw std::invalid_argument("BvhMotion: m_per_unit must be positive");
  for (int s = 0; s < kSegmentCount; ++s) {
    joint_[s] = -1;
    for (std::string_view n : aliases()[s]) {
      const int j = clip_.find(n);
      if (j >= 0) {
        joint_[s] = j;
        break;
      }
    }
  }
  if (joint_[0] < 0) joint_[0] = clip_.joints.empty() ? -1 : 0;  // the root is the hips
  if (joint_[0] < 0) throw std::runtime_error("BVH has no joints");
  // Rest pose (all channels zero): global positions in our axes, file units.
  std::vector<Eigen::Quaterniond> rq;
  std::vector<Eigen::Vector3d> rp;
  {
    BvhClip rest = clip_;
    rest.frame_count = 0;
    rest.global_pose(0, rq, rp);
  }
  const Eigen::Quaterniond c = q_bvh_body();
  auto ours = [&](const Eigen::Vector3d& v_bvh) { return Eigen::Vector3d(c.conjugate() * v_bvh); };
  std::vector<Eigen::Vector3d> rest_pos(rp.size());
  for (size_t i = 0; i < rp.size(); ++i)
    rest_pos[i] = ours(rp[i]);

  // Height estimate from the rest pose (joints and end sites).
  double zmin = 1e300, zmax = -1e300;
  for (size_t i = 0; i < rp.size(); ++i) {
    zmin = std::min(zmin, rest_pos[i].z());
    zmax = std::max(zmax, rest_pos[i].z());
    if (clip_.joints[i].has_end_site) {
      const double ze = (rest_pos[i] + ours(clip_.joints[i].end_site)).z();
      zmin = std::min(zmin, ze);
      zmax = std::max(zmax, ze);
    }
  }
  double height_m = (zmax - zmin) * m_per_unit_;
  if (!(height_m > 0.5 && height_m < 2.6)) height_m = 1.75;
  const BodyDimensions nominal = body_dimensions_from_height(1.75);
  dims_ = body_dimensions_from_height(height_m);

  // Rest alignment: rotation from our N-pose bone direction to the file's rest bone direction.
  for (int s = 0; s < kSegmentCount; ++s) {
    q_fix_[s] = Eigen::Quaterniond::Identity();
    const int j = joint_[s];
    if (j < 0) continue;
    Eigen::Vector3d ours_dir, file_dir = Eigen::Vector3d::Zero();
    const int cs = s == 0 ? index(Segment::torso) : kChainChild[s];
    if (cs >= 0) {
      ours_dir = nominal.joint_offset_m[cs];
      if (joint_[cs] >= 0) file_dir = rest_pos[joint_[cs]] - rest_pos[j];
    } else {
      ours_dir = nominal.end_offset_m[s];
      if (clip_.joints[j].has_end_site) file_dir = ours(clip_.joints[j].end_site);
    }
    if (file_dir.norm() > 1e-9 && ours_dir.norm() > 1e-9)
      q_fix_[s] = Eigen::Quaterniond::FromTwoVectors(ours_dir, file_dir);
  }
  // Dimensions: offsets expressed in the parent segment's N-pose frame.
  for (int s = 0; s < kSegmentCount; ++s) {
    const int j = joint_[s];
    if (j < 0) continue;
    if (s == 0) {
      dims_.joint_offset_m[0] = Eigen::Vector3d(0, 0, (rest_pos[j].z() - zmin) * m_per_unit_);
    } else {
      int p = kSegmentParent[s];
      while (p > 0 && joint_[p] < 0)
        p = kSegmentParent[p];
      if (joint_[p] >= 0 && p == kSegmentParent[s])
        dims_.joint_offset_m[s] =
            q_fix_[p].conjugate() * (rest_pos[j] - rest_pos[joint_[p]]) * m_per_unit_;
    }
    if (clip_.joints[j].has_end_site)
      dims_.end_offset_m[s] = q_fix_[s].conjugate() * ours(clip_.joints[j].end_site) * m_per_unit_;
  }
  gq_.reserve(clip_.joints.size());
  gp_.reserve(clip_.joints.size());
}

void BvhMotion::frame(int k, std::array<Eigen::Quaterniond, kSegmentCount>& q,
                      Eigen::Vector3d& p_root_m) const {
  if (k < 0 || k >= clip_.frame_count) throw std::out_of_range("BvhMotion: frame index");
  clip_.global_pose(k, gq_, gp_);
  const Eigen::Quaterniond c = q_bvh_body();
  for (int s = 0; s < kSegmentCount; ++s) {
    const int j = joint_[s];
    if (j >= 0)
      q[s] = (c.conjugate() * gq_[j] * c * q_fix_[s]).normalized();
    else
      q[s] = q[kSegmentParent[s]];
  }
  p_root_m = c.conjugate() * gp_[joint_[0]] * m_per_unit_;
}

void BvhMotion::to_pose_frame(int k, PoseFrame& out) const {
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  Eigen::Vector3d root;
  frame(k, q, root);
  out.frame = static_cast<uint64_t>(k);
  out.t_ns = static_cast<int64_t>(std::llround(k * clip_.frame_time_s * 1e9));
  pose_from_earth_orientations(dims_, q, root, out);
  for (int s = 0; s < kSegmentCount; ++s) {
    out.joint_violation_deg[s] = 0;
    out.segment_flags[s] = joint_[s] >= 0 ? kSegTracked : kSegInferred;
  }
}

}  // namespace mocap
