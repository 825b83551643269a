// Avatar geometry: capsules per segment from the pose and the body dimensions.
#include "mocap/viewer/avatar_geometry.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

namespace mocap::viewer {
namespace {

using V3 = Eigen::Vector3f;

Eigen::Quaternionf quat(const std::array<float, 4>& q) {
  return Eigen::Quaternionf(q[0], q[1], q[2], q[3]).normalized();
}
V3 pos(const std::array<float, 3>& p) {
  return V3(p[0], p[1], p[2]);
}
std::array<float, 3> arr(const V3& v) {
  return {v.x(), v.y(), v.z()};
}

/// Solid radius of each segment's main capsule for a 1.75 m person, metres.
constexpr std::array<float, kSegmentCount> kRadius175 = {0.085f, 0.115f, 0.045f,
                                                         0.095f,  // pelvis, torso, neck, head
                                                         0.048f, 0.040f, 0.036f,   // left arm
                                                         0.048f, 0.040f, 0.036f,   // right arm
                                                         0.068f, 0.052f, 0.036f,   // left leg
                                                         0.068f, 0.052f, 0.036f};  // right leg

void push(std::vector<CapsuleInstance>& out, const V3& a, const V3& b, float r,
          const std::array<float, 3>& rgb) {
  CapsuleInstance c;
  c.a_m = arr(a);
  c.b_m = arr(b);
  c.radius_m = r;
  c.rgba = {rgb[0], rgb[1], rgb[2], 1.0f};
  out.push_back(c);
}

bool is_left(int s) {
  return s == index(Segment::upper_arm_l) || s == index(Segment::forearm_l) ||
         s == index(Segment::hand_l) || s == index(Segment::thigh_l) ||
         s == index(Segment::shank_l) || s == index(Segment::foot_l);
}
bool is_right(int s) {
  return s == index(Segment::upper_arm_r) || s == index(Segment::forearm_r) ||
         s == index(Segment::hand_r) || s == index(Segment::thigh_r) ||
         s == index(Segment::shank_r) || s == index(Segment::foot_r);
}

}  // namespace

std::array<float, 3> segment_rgb(int s, uint32_t flags) {
  if (flags & kSegLimitViolated) return kRgbLimitViolated;
  if (flags & kSegStale) return kRgbStale;
  if (flags & kSegMagDisturbed) return kRgbMagDisturbed;
  if (is_left(s)) return {0.38f, 0.62f, 0.95f};
  if (is_right(s)) return {0.96f, 0.58f, 0.30f};
  return {0.86f, 0.76f, 0.58f};
}

void segment_label(const PoseFrame& f, int s, std::array<char, 32>& out) {
  out[0] = '\0';
  const uint32_t flags = f.segment_flags[s];
  if (flags & kSegLimitViolated) {
    std::snprintf(out.data(), out.size(), "LIMIT %.0f DEG",
                  static_cast<double>(f.joint_violation_deg[s]));
  } else if (flags & kSegStale) {
    std::snprintf(out.data(), out.size(), "STALE");
  } else if (flags & kSegMagDisturbed) {
    std::snprintf(out.data(), out.size(), "MAG");
  }
}

bool pose_is_finite(const PoseFrame& f) {
  for (int s = 0; s < kSegmentCount; ++s) {
    for (float v : f.q_earth_segment[s])
      if (!std::isfinite(v)) return false;
    for (float v : f.p_earth_segment_m[s])
      if (!std::isfinite(v)) return false;
    const auto& q = f.q_earth_segment[s];
    if (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-6f) return false;
  }
  return true;
}

Eigen::Vector3f segment_midpoint(const PoseFrame& f, const BodyDimensions& dims, int s) {
  const V3 end = dims.end_offset_m[s].cast<float>();
  return pos(f.p_earth_segment_m[s]) + quat(f.q_earth_segment[s]) * (0.5f * end);
}

void append_avatar(const PoseFrame& f, const BodyDimensions& dims, const AvatarStyle& style,
                   std::vector<CapsuleInstance>& out) {
  if (!pose_is_finite(f)) return;
  const float scale = static_cast<float>(dims.height_m / 1.75);
  auto local = [&](int s, const V3& v) -> V3 {
    return pos(f.p_earth_segment_m[s]) + quat(f.q_earth_segment[s]) * v;
  };
  auto offset = [&](int s) { return dims.joint_offset_m[s].cast<float>().eval(); };
  const float stick_r = 0.014f * scale, joint_r = 0.028f * scale;

  for (int s = 0; s < kSegmentCount; ++s) {
    const auto rgb = segment_rgb(s, f.segment_flags[s]);
    const V3 end = dims.end_offset_m[s].cast<float>();
    const float r = style.stick ? stick_r : kRadius175[s] * scale;
    V3 a = V3::Zero(), b = end;
    if (s == index(Segment::head) && !style.stick) {
      a = 0.40f * end;  // a round head around the middle of the neck-to-crown segment
      b = 0.58f * end;
    } else if ((s == index(Segment::foot_l) || s == index(Segment::foot_r)) && !style.stick) {
      a = V3(-0.015f * scale, 0, end.z() + r);  // heel resting on the floor
      b = V3(end.x() - r, 0, end.z() + r);      // toes
    } else if (!style.stick && s != index(Segment::pelvis) && s != index(Segment::torso)) {
      // Limbs end where the next segment starts; leave the joint visible as a slight neck.
      b = end;
    }
    push(out, local(s, a), local(s, b), r, rgb);
    if (style.stick) push(out, local(s, V3::Zero()), local(s, V3::Zero()), joint_r, rgb);
  }
  // Cross bars: hips (between the thigh joints, pelvis frame), shoulders (torso frame).
  const int pelvis = index(Segment::pelvis), torso = index(Segment::torso);
  const float hip_r = style.stick ? stick_r : 0.075f * scale;
  const float shoulder_r = style.stick ? stick_r : 0.058f * scale;
  push(out, local(pelvis, offset(index(Segment::thigh_l))),
       local(pelvis, offset(index(Segment::thigh_r))), hip_r,
       segment_rgb(pelvis, f.segment_flags[pelvis]));
  push(out, local(torso, offset(index(Segment::upper_arm_l))),
       local(torso, offset(index(Segment::upper_arm_r))), shoulder_r,
       segment_rgb(torso, f.segment_flags[torso]));

  if (style.sensor_axes) {
    const float len = 0.14f * scale, r = 0.006f * scale;
    const std::array<std::array<float, 3>, 3> rgb = {
        {{0.95f, 0.15f, 0.15f}, {0.15f, 0.85f, 0.20f}, {0.20f, 0.35f, 1.0f}}};
    for (int s = 0; s < kSegmentCount; ++s) {
      const V3 mid = 0.5f * dims.end_offset_m[s].cast<float>();
      for (int k = 0; k < 3; ++k) {
        V3 axis = V3::Zero();
        axis[k] = len;
        push(out, local(s, mid), local(s, mid + axis), r, rgb[k]);
      }
    }
  }
}

void append_earth_axes(float length_m, std::vector<CapsuleInstance>& out) {
  const float r = 0.012f;
  push(out, V3(0, 0, 0), V3(length_m, 0, 0), r, {0.95f, 0.15f, 0.15f});
  push(out, V3(0, 0, 0), V3(0, length_m, 0), r, {0.15f, 0.85f, 0.20f});
  push(out, V3(0, 0, 0), V3(0, 0, length_m), r, {0.20f, 0.35f, 1.0f});
}

}  // namespace mocap::viewer
