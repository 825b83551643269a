// Procedural walking-in-place performer and its sensor status, for the demo source.
#include "mocap/viewer/synthetic_source.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>

#include "mocap/viewer/camera.hpp"

namespace mocap::viewer {
namespace {

using Q = Eigen::Quaternionf;
using V3 = Eigen::Vector3f;
constexpr float kPi = 3.14159265358979f;

Q about(const V3& axis, float rad) {
  return Q(Eigen::AngleAxisf(rad, axis));
}

}  // namespace

SyntheticSource::SyntheticSource(int avatars, BodyDimensions dims)
    : avatars_(avatars < 1 ? 1 : avatars), dims_(std::move(dims)) {}

void SyntheticSource::pose_at(int i, double t_s, PoseFrame& f) const {
  reset_pose(f);
  const float phase = static_cast<float>(i) * 0.73f;
  const float w = 2 * kPi * 0.9f;  // stride frequency, Hz
  const float t = static_cast<float>(t_s);
  const float s = std::sin(w * t + phase), c = std::cos(w * t + phase);
  const float deg = kPi / 180;

  std::array<Q, kSegmentCount> q;
  q.fill(Q::Identity());
  const float heading = (avatars_ > 1 ? static_cast<float>(i) * 0.9f : 0.0f) + 8 * deg * s;
  q[index(Segment::pelvis)] = about(V3::UnitZ(), heading) * about(V3::UnitX(), 3 * deg * c);
  q[index(Segment::torso)] = about(V3::UnitZ(), -10 * deg * s) * about(V3::UnitY(), 4 * deg);
  q[index(Segment::head)] = about(V3::UnitZ(), 6 * deg * std::sin(0.4f * w * t));
  // Legs: rotation about y by a negative angle swings the foot forward (+x).
  q[index(Segment::thigh_l)] = about(V3::UnitY(), -25 * deg * s);
  q[index(Segment::thigh_r)] = about(V3::UnitY(), 25 * deg * s);
  q[index(Segment::shank_l)] = about(V3::UnitY(), 35 * deg * std::max(0.0f, -c));
  q[index(Segment::shank_r)] = about(V3::UnitY(), 35 * deg * std::max(0.0f, c));
  // Arms swing against the legs, slightly abducted; elbows bend forward.
  q[index(Segment::upper_arm_l)] = about(V3::UnitX(), 12 * deg) * about(V3::UnitY(), 22 * deg * s);
  q[index(Segment::upper_arm_r)] =
      about(V3::UnitX(), -12 * deg) * about(V3::UnitY(), -22 * deg * s);
  q[index(Segment::forearm_l)] = about(V3::UnitY(), -(25 + 15 * s) * deg);
  q[index(Segment::forearm_r)] = about(V3::UnitY(), -(25 - 15 * s) * deg);

  const V3 origin = crowd_origin(i, avatars_);
  const float bob = 0.02f * std::abs(c) - 0.02f;
  const V3 pelvis = origin + V3(0, 0, static_cast<float>(dims_.joint_offset_m[0].z()) + bob);
  pose_from_joint_rotations(dims_, q, pelvis, f);

  f.frame = frame_;
  f.t_ns = static_cast<int64_t>(t_s * 1e9);
  f.flags = kFrameDemo | kFrameCalibrated;
  for (int k = 0; k < kSegmentCount; ++k)
    f.segment_flags[k] = kSegTracked;
  if (i != 0) return;

  // Avatar 0 shows every state once per 6 s: 0-2 s elbow limit, 2-4 s stale shank, 4-6 s
  // disturbed magnetometer on the right upper arm.
  const double cycle = std::fmod(std::max(0.0, t_s), 6.0);
  const int limit = index(Segment::forearm_l), stale = index(Segment::shank_r),
            mag = index(Segment::upper_arm_r);
  if (cycle < 2) {
    f.segment_flags[limit] |= kSegLimitViolated;
    f.joint_violation_deg[limit] = static_cast<float>(5 + 5 * cycle);
  } else if (cycle < 4) {
    f.segment_flags[stale] = kSegStale;
  } else {
    f.segment_flags[mag] |= kSegMagDisturbed;
  }
  const std::array<Segment, 10> worn = {
      Segment::pelvis,    Segment::torso,       Segment::head,      Segment::upper_arm_l,
      Segment::forearm_l, Segment::upper_arm_r, Segment::forearm_r, Segment::thigh_l,
      Segment::shank_l,   Segment::shank_r};
  f.sensor_count = worn.size();
  for (size_t k = 0; k < worn.size(); ++k) {
    SensorStatus& st = f.sensors[k];
    const int seg = index(worn[k]);
    std::snprintf(st.name, sizeof st.name, "imu%zu", k);
    st.segment = static_cast<int8_t>(seg);
    const bool is_stale = (f.segment_flags[seg] & kSegStale) != 0;
    st.state = is_stale ? 3 : 2;
    st.rate_hz = is_stale ? 0.0f : 100.0f;
    st.last_age_ms = is_stale ? static_cast<float>((cycle - 2) * 1000) : 4.0f;
    st.flags = static_cast<uint16_t>(f.segment_flags[seg] & 0xffff);
    st.drops = static_cast<uint32_t>(k);
  }
}

bool SyntheticSource::poll(double t_s, std::vector<PoseFrame>& frames) {
  if (paused_) {
    offset_s_ -= t_s - last_t_s_;  // freeze the animation clock
  }
  last_t_s_ = t_s;
  const double t = t_s + offset_s_;
  frames.resize(static_cast<size_t>(avatars_));
  ++frame_;
  for (int i = 0; i < avatars_; ++i)
    pose_at(i, t, frames[static_cast<size_t>(i)]);
  return true;
}

std::string SyntheticSource::status() const {
  return "SYNTHETIC DEMO, " + std::to_string(avatars_) + (avatars_ == 1 ? " AVATAR" : " AVATARS");
}

}  // namespace mocap::viewer
