// Pose interpolation, orientation tracks with dropout bridging, fixed-rate resampling.
#include "mocap/skeleton/interpolation.hpp"

#include <cmath>
#include <stdexcept>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

void interpolate_pose(const PoseFrame& a, const PoseFrame& b, double t, PoseFrame& out) {
  const PoseFrame& near = t < 0.5 ? a : b;
  const double u = 1.0 - t;
  PoseFrame r = near;
  r.t_ns = a.t_ns + static_cast<int64_t>(std::llround(static_cast<double>(b.t_ns - a.t_ns) * t));
  for (int s = 0; s < kSegmentCount; ++s) {
    r.q_earth_segment[s] = to_wxyz(
        slerp_shortest(from_wxyz(a.q_earth_segment[s]), from_wxyz(b.q_earth_segment[s]), t));
    r.q_parent_segment[s] = to_wxyz(
        slerp_shortest(from_wxyz(a.q_parent_segment[s]), from_wxyz(b.q_parent_segment[s]), t));
    for (int k = 0; k < 3; ++k)
      r.p_earth_segment_m[s][k] =
          static_cast<float>(u * a.p_earth_segment_m[s][k] + t * b.p_earth_segment_m[s][k]);
    r.joint_violation_deg[s] =
        static_cast<float>(u * a.joint_violation_deg[s] + t * b.joint_violation_deg[s]);
  }
  out = r;
}

bool OrientationTrack::push(int64_t t_ns, const Eigen::Quaterniond& q) {
  const double n = q.norm();
  if (!std::isfinite(n) || n < 0.5) return false;
  if (count_ > 0 && t_ns <= t_at(count_ - 1)) return false;
  if (count_ > 0 && t_ns - t_at(count_ - 1) > nominal_gap_ns_) t_after_gap_ns_ = t_ns;
  if (count_ == kCapacity) {
    head_ = (head_ + 1) % kCapacity;
    --count_;
  }
  const int slot = (head_ + count_) % kCapacity;
  t_[slot] = t_ns;
  q_[slot] = Eigen::Quaterniond(q.coeffs() / n);
  ++count_;
  return true;
}

OrientationTrack::Sample OrientationTrack::sample(int64_t t_ns) const {
  Sample s;
  if (count_ == 0) return s;
  s.valid = true;
  if (t_ns <= t_at(0)) {
    s.q = q_at(0);
    s.held = t_ns < t_at(0);
    return s;
  }
  if (t_ns >= t_at(count_ - 1)) {
    s.q = q_at(count_ - 1);
    s.held = t_ns > t_at(count_ - 1);
    return s;
  }
  const int lo = key_before(t_ns), hi = lo + 1;
  if (t_at(lo) == t_ns) {  // a key itself: measured, not bridged
    s.q = q_at(lo);
    return s;
  }
  const int64_t gap = t_at(hi) - t_at(lo);
  if (gap > max_bridge_ns_) {
    s.q = q_at(lo);
    s.held = true;
    return s;
  }
  s.bridged = gap > nominal_gap_ns_;
  s.q = slerp_shortest(q_at(lo), q_at(hi),
                       static_cast<double>(t_ns - t_at(lo)) / static_cast<double>(gap));
  return s;
}

int OrientationTrack::key_before(int64_t t_ns) const {
  int lo = 0, hi = count_ - 1;  // binary search
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (t_at(mid) <= t_ns)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

bool OrientationTrack::bridged(int64_t t_ns, Eigen::Quaterniond& q) const {
  if (t_ns >= t_after_gap_ns_) return false;  // the frames of a stream without dropouts
  const Sample s = sample(t_ns);
  if (!s.bridged) return false;
  q = s.q;
  return true;
}

PoseResampler::PoseResampler(double rate_hz) {
  if (!(rate_hz > 0 && rate_hz <= 10000))
    throw std::invalid_argument("PoseResampler: rate must be in (0, 10000] Hz");
  period_ns_ = static_cast<int64_t>(std::llround(1e9 / rate_hz));
}

void PoseResampler::push(const PoseFrame& f) {
  if (have_ > 0 && f.t_ns <= cur_.t_ns) return;
  prev_ = cur_;
  cur_ = f;
  if (have_ == 0) t_next_ns_ = f.t_ns;
  if (have_ < 2) ++have_;
}

bool PoseResampler::next(PoseFrame& out) {
  if (have_ == 0) return false;
  if (have_ == 1) {
    if (t_next_ns_ != cur_.t_ns) return false;
    out = cur_;
  } else {
    if (t_next_ns_ > cur_.t_ns) return false;
    if (t_next_ns_ < prev_.t_ns) t_next_ns_ = prev_.t_ns;  // older than what we keep: skip ahead
    const double t =
        static_cast<double>(t_next_ns_ - prev_.t_ns) / static_cast<double>(cur_.t_ns - prev_.t_ns);
    interpolate_pose(prev_, cur_, t, out);
  }
  out.t_ns = t_next_ns_;
  out.frame = out_frame_++;
  t_next_ns_ += period_ns_;
  return true;
}

}  // namespace mocap
