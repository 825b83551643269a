// A virtual performer who reacts: the test tells it which joint to move when it reads a prompt,
// and every simulated sensor strapped to a segment feels that segment's motion. The body is our
// 16-segment tree standing in the N-pose (every segment frame = the earth frame, sensors mounted
// square on their segments); moving the joint of segment s turns s and everything below it
// (an elbow turns forearm and hand alike), A sin(2 pi f t) about the joint's own axis, whole
// cycles only (stop() lets the current cycle finish, so orientations stay continuous). Its
// motions are read at the moment of the call (a live performer: the device time is not used).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/core/units.hpp"
#include "mocap/devsim/sim_device.hpp"

namespace mocap::test {

class LivePerformer {
 public:
  /// Starts turning the joint of `segment` now (if it is not already turning).
  void move(int segment, double amplitude_rad = 0.7, double freq_hz = 1.5) {
    std::lock_guard lk(mu_);
    const int64_t now = monotonic_ns();
    for (const Turn& t : turns_)
      if (t.segment == segment && now < t.t_end_ns) return;
    turns_.push_back({segment, now, kNever, amplitude_rad, freq_hz});
  }
  /// Every joint finishes its current cycle and rests.
  void stop() {
    std::lock_guard lk(mu_);
    const int64_t now = monotonic_ns();
    for (Turn& t : turns_) {
      if (t.t_end_ns != kNever) continue;
      const double period_ns = 1e9 / t.freq_hz;
      const double cycles = std::ceil(static_cast<double>(now - t.t0_ns) / period_ns);
      t.t_end_ns = t.t0_ns + static_cast<int64_t>(std::max(1.0, cycles) * period_ns);
    }
  }
  /// True once no joint turns any more.
  bool resting() const {
    std::lock_guard lk(mu_);
    const int64_t now = monotonic_ns();
    return std::none_of(turns_.begin(), turns_.end(),
                        [&](const Turn& t) { return now < t.t_end_ns; });
  }

  /// Segment s's orientation (earth from segment) and its angular velocity in the segment
  /// frame, now.
  void state(int s, Eigen::Quaterniond& q_earth_segment, Eigen::Vector3d& gyr_rad_s) const {
    std::array<double, kSegmentCount> angle{}, rate{};
    {
      std::lock_guard lk(mu_);
      const int64_t now = monotonic_ns();
      for (const Turn& t : turns_) {
        if (now < t.t0_ns || now >= t.t_end_ns) continue;
        const double w = 2 * M_PI * t.freq_hz, ts = static_cast<double>(now - t.t0_ns) * 1e-9;
        angle[t.segment] += t.amplitude_rad * std::sin(w * ts);
        rate[t.segment] += t.amplitude_rad * w * std::cos(w * ts);
      }
    }
    std::vector<int> path;  // root first
    for (int k = s; k != kNoParent; k = kSegmentParent[k])
      path.insert(path.begin(), k);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    Eigen::Vector3d w_earth = Eigen::Vector3d::Zero();
    for (int k : path) {
      const Eigen::Vector3d axis = joint_axis(k);
      w_earth += q * (axis * rate[k]);
      q = q * Eigen::Quaterniond(Eigen::AngleAxisd(angle[k], axis));
    }
    q_earth_segment = q.normalized();
    gyr_rad_s = q_earth_segment.conjugate() * w_earth;
  }

  /// The axis each joint turns about, in its parent's frame (x forward, y left, z up): hips
  /// turn, arms rise sideways, everything else bends forward.
  static Eigen::Vector3d joint_axis(int s) {
    if (s == index(Segment::pelvis)) return Eigen::Vector3d::UnitZ();
    if (s == index(Segment::upper_arm_l)) return -Eigen::Vector3d::UnitX();
    if (s == index(Segment::upper_arm_r)) return Eigen::Vector3d::UnitX();
    return Eigen::Vector3d::UnitY();
  }

  /// The motion a sensor on segment s feels (for SimulatedDevice / SimSlimeTracker).
  std::shared_ptr<const Motion> motion_of(int s) const {
    return std::make_shared<SegmentMotion>(*this, s);
  }

 private:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  struct Turn {
    int segment;
    int64_t t0_ns, t_end_ns;
    double amplitude_rad, freq_hz;
  };

  class SegmentMotion final : public Motion {
   public:
    SegmentMotion(const LivePerformer& p, int s) : p_(p), s_(s) {}
    ImuSample at(int64_t t_device_ns) const override {
      ImuSample out;
      Eigen::Quaterniond q;
      p_.state(s_, q, out.gyr_rad_s);
      out.t_device_ns = t_device_ns;
      out.q_device_sensor = q;
      out.acc_m_s2 = q.conjugate() * Eigen::Vector3d(0, 0, kStandardGravity_m_s2);
      out.mag_uT = q.conjugate() * Eigen::Vector3d(0.0, 20.0, -40.0);
      out.valid = kFieldGyr | kFieldAcc | kFieldMag | kFieldQuat;
      out.flags = kFlagSynthetic;
      return out;
    }

   private:
    const LivePerformer& p_;
    int s_;
  };

  mutable std::mutex mu_;
  std::vector<Turn> turns_;
};

}  // namespace mocap::test
