// Dropout bridging: a forearm turning at a constant rate loses its sensor for 200 ms (the live
// pipeline held it); the bridge slerps it across the gap, recomputes the wrist's position and
// the joint rotations, and leaves a 700 ms gap held as recorded.
#include <gtest/gtest.h>

#include <vector>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/dropout_bridge.hpp"
#include "mocap/skeleton/forward_kinematics.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {
namespace {

constexpr int kForearm = index(Segment::forearm_l);
constexpr int64_t kFrameNs = 10'000'000;  // 100 Hz

Eigen::Quaterniond forearm_at(double t_s) {  // elbow flexing at 90 deg/s
  return Eigen::Quaterniond(Eigen::AngleAxisd(-0.5 * M_PI * t_s, Eigen::Vector3d::UnitY()));
}

/// Frames at 100 Hz for 3 s; the forearm's sensor is silent in [gap_from_s, gap_to_s): its
/// orientation is held and its sample age grows, as the pipeline records it.
std::vector<PoseFrame> recording(const BodyDimensions& dims, double gap_from_s, double gap_to_s) {
  std::vector<PoseFrame> out;
  double last_sample_s = 0;
  for (int k = 0; k <= 300; ++k) {
    const double t_s = k * 0.01;
    if (!(t_s >= gap_from_s && t_s < gap_to_s)) last_sample_s = t_s;
    std::array<Eigen::Quaterniond, kSegmentCount> q;
    q.fill(Eigen::Quaterniond::Identity());
    q[kForearm] = forearm_at(last_sample_s);
    PoseFrame f;
    reset_pose(f);
    f.t_ns = k * kFrameNs;
    pose_from_earth_orientations(dims, q, Eigen::Vector3d(0, 0, 1), f);
    for (int s = 0; s < kSegmentCount; ++s)
      f.segment_flags[s] = kSegTracked;
    f.sensor_count = 1;
    f.sensors[0].segment = kForearm;
    f.sensors[0].last_age_ms = static_cast<float>((t_s - last_sample_s) * 1e3);
    out.push_back(f);
  }
  return out;
}

std::vector<PoseFrame> bridged(const BodyDimensions& dims, const std::vector<PoseFrame>& in,
                               long& count) {
  DropoutBridge bridge(dims);
  std::vector<PoseFrame> out;
  PoseFrame f;
  for (const PoseFrame& p : in) {
    bridge.push(p);
    while (bridge.next(f))
      out.push_back(f);
  }
  bridge.finish();
  while (bridge.next(f))
    out.push_back(f);
  count = bridge.bridged();
  return out;
}

TEST(DropoutBridge, SlerpsAShortGapAndKeepsALongOneHeld) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  long count = 0;
  const auto in = recording(dims, 1.0, 1.2);
  const auto out = bridged(dims, in, count);
  ASSERT_EQ(out.size(), in.size());
  EXPECT_EQ(count, 20);  // the frames at 1.00 .. 1.19 s
  double worst_in_deg = 0, worst_out_deg = 0, worst_wrist_m = 0;
  for (size_t k = 0; k < out.size(); ++k) {
    EXPECT_EQ(out[k].t_ns, in[k].t_ns);
    const double t_s = static_cast<double>(out[k].t_ns) * 1e-9;
    const Eigen::Quaterniond truth = forearm_at(t_s);
    worst_in_deg =
        std::max(worst_in_deg,
                 truth.angularDistance(from_wxyz(in[k].q_earth_segment[kForearm])) * kDegPerRad);
    worst_out_deg =
        std::max(worst_out_deg,
                 truth.angularDistance(from_wxyz(out[k].q_earth_segment[kForearm])) * kDegPerRad);
    // The elbow's joint rotation and the wrist's position follow the bridged forearm.
    EXPECT_LT(from_wxyz(out[k].q_parent_segment[kForearm])
                  .angularDistance(from_wxyz(out[k].q_earth_segment[kForearm])),
              1e-5);
    const int hand = index(Segment::hand_l);
    const Eigen::Vector3d elbow(out[k].p_earth_segment_m[kForearm][0],
                                out[k].p_earth_segment_m[kForearm][1],
                                out[k].p_earth_segment_m[kForearm][2]);
    const Eigen::Vector3d wrist(out[k].p_earth_segment_m[hand][0],
                                out[k].p_earth_segment_m[hand][1],
                                out[k].p_earth_segment_m[hand][2]);
    worst_wrist_m =
        std::max(worst_wrist_m, (wrist - (elbow + truth * dims.joint_offset_m[hand])).norm());
  }
  EXPECT_GT(worst_in_deg, 15.0);  // held for 200 ms at 90 deg/s
  EXPECT_LT(worst_out_deg, 0.01);
  EXPECT_LT(worst_wrist_m, 1e-5);

  // A gap longer than max_bridge (0.5 s) is left as recorded.
  const auto long_in = recording(dims, 1.0, 1.7);
  const auto long_out = bridged(dims, long_in, count);
  EXPECT_EQ(count, 0);
  for (size_t k = 0; k < long_out.size(); ++k)
    EXPECT_EQ(long_out[k].q_earth_segment[kForearm], long_in[k].q_earth_segment[kForearm]);
}

}  // namespace
}  // namespace mocap
