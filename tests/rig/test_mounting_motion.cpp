// The mounting motion (rig/mounting_motion.hpp): after an N-pose, two bows with bent knees and
// curling elbows give every segment that tilts its facing, whatever the strap and whatever
// heading each sensor's (6D) filter frame has; the feet (which stay flat) and a segment that did
// not move get none.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "mocap/core/units.hpp"
#include "mocap/rig/mounting_motion.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {
namespace {

Eigen::Quaterniond about(double angle_rad, const Eigen::Vector3d& axis) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis));
}

/// Pitch of each segment (about the body's left axis; positive leans its top forward) per unit
/// of the bow: the trunk, head and shanks lean forward, the thighs' and forearms' far ends
/// swing forward, the upper arms lean with the trunk.
double pitch_per_bow(Segment s) {
  switch (s) {
    case Segment::pelvis:
      return 0.5;
    case Segment::torso:
      return 0.6;
    case Segment::head:
      return 0.7;
    case Segment::upper_arm_l:
    case Segment::upper_arm_r:
      return 0.4;
    case Segment::forearm_l:
    case Segment::forearm_r:
    case Segment::hand_l:
    case Segment::hand_r:
      return -1.0;
    case Segment::thigh_l:
    case Segment::thigh_r:
      return -0.8;
    case Segment::shank_l:
    case Segment::shank_r:
      return 0.6;
    default:
      return 0.0;  // neck (no sensor), feet (flat)
  }
}

struct Strapped {
  std::array<Eigen::Quaterniond, kSegmentCount> q_seg_sensor, q_frame;
};

Strapped random_straps(uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  Strapped st;
  for (int s = 0; s < kSegmentCount; ++s) {
    st.q_seg_sensor[s] = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    st.q_frame[s] = about(yaw(rng), Eigen::Vector3d::UnitZ());
  }
  return st;
}

/// The segment's orientation at time t of the motion (the body facing body_yaw_rad).
Eigen::Quaterniond segment_at(int s, double t, double body_yaw_rad) {
  const double bow = 0.5 * (1 - std::cos(2 * M_PI * t / 2.5));  // two bows in 5 s
  const double sway = 0.05 * std::sin(3.0 * t);                 // a little sideways wobble
  return about(body_yaw_rad, Eigen::Vector3d::UnitZ()) * about(sway, Eigen::Vector3d::UnitX()) *
         about(bow * pitch_per_bow(static_cast<Segment>(s)), Eigen::Vector3d::UnitY());
}

TEST(MountingMotion, FacingsOfEverySegmentThatTiltsForAnyStrap) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Strapped st = random_straps(seed);
    const double body_yaw = 0.3 * seed;
    PoseCapture c;
    const int64_t t0_ns = 10'000'000'000;
    c.t_end_ns = t0_ns;
    for (int s = 0; s < kSegmentCount; ++s) {
      c.have[s] = static_cast<Segment>(s) != Segment::neck;
      c.q_earth_sensor[s] = st.q_frame[s] * segment_at(s, 0, body_yaw) * st.q_seg_sensor[s];
    }
    MountingMotion m;
    m.start(c, t0_ns, 5.0);
    int64_t t_ns = t0_ns;
    for (int n = 0; !m.done(t_ns); ++n) {
      t_ns = t0_ns + n * 10'000'000LL;
      const double t = n * 0.01;
      for (int s = 0; s < kSegmentCount; ++s)
        m.add(s, st.q_frame[s] * segment_at(s, t, body_yaw) * st.q_seg_sensor[s], t_ns);
    }
    const auto facing = m.finish();
    EXPECT_FALSE(m.active());
    for (int s = 0; s < kSegmentCount; ++s) {
      const std::string what = std::string(kSegmentNames[s]) + " seed " + std::to_string(seed);
      if (MountingMotion::tilt_sign(s) == 0) {
        EXPECT_FALSE(facing[s].known()) << what;
        continue;
      }
      ASSERT_TRUE(facing[s].known()) << what;
      EXPECT_EQ(facing[s].source, AlignSource::motion);
      // The segment's forward axis in the pose, in the sensor's own filter frame.
      const Eigen::Vector3d fwd =
          st.q_frame[s] * segment_at(s, 0, body_yaw) * Eigen::Vector3d::UnitX();
      const double err_deg =
          std::abs(wrap_angle_rad(facing[s].yaw_rad - heading_of_rad(fwd))) * kDegPerRad;
      EXPECT_LT(err_deg, 3.0) << what;
      EXPECT_LE(err_deg, 3 * facing[s].sigma_deg) << what;
    }
  }
}

TEST(MountingMotion, NoFacingWithoutMotion) {
  const Strapped st = random_straps(5);
  PoseCapture c;
  for (int s = 0; s < kSegmentCount; ++s) {
    c.have[s] = true;
    c.q_earth_sensor[s] = st.q_frame[s] * st.q_seg_sensor[s];
  }
  MountingMotion m;
  m.start(c, 0, 5.0);
  for (int n = 0; n <= 500; ++n)
    for (int s = 0; s < kSegmentCount; ++s)
      m.add(s, c.q_earth_sensor[s], n * 10'000'000LL);
  for (const Facing& f : m.finish())
    EXPECT_FALSE(f.known());
}

}  // namespace
}  // namespace mocap::rig
