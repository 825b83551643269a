// Dropout bridging of a pose stream (see dropout_bridge.hpp).
#include "mocap/skeleton/dropout_bridge.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/skeleton/forward_kinematics.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {
namespace {

/// Per segment, the age of the newest sample of the (first listed) sensor driving it, ns; -1 if
/// none drives it.
std::array<int64_t, kSegmentCount> sample_ages_ns(const PoseFrame& f) {
  std::array<int64_t, kSegmentCount> age;
  age.fill(-1);
  const uint32_t n = std::min<uint32_t>(f.sensor_count, kMaxSensors);
  for (uint32_t k = 0; k < n; ++k) {
    const SensorStatus& st = f.sensors[k];
    if (st.segment >= 0 && st.segment < kSegmentCount && age[st.segment] < 0 &&
        std::isfinite(st.last_age_ms) && st.last_age_ms >= 0)
      age[st.segment] = static_cast<int64_t>(std::llround(st.last_age_ms * 1e6));
  }
  return age;
}

}  // namespace

DropoutBridge::DropoutBridge(const BodyDimensions& dims, int64_t nominal_gap_ns,
                             int64_t max_bridge_ns)
    : dims_(dims), max_bridge_ns_(max_bridge_ns) {
  for (auto& t : tracks_)
    t = OrientationTrack(nominal_gap_ns, max_bridge_ns);
}

void DropoutBridge::push(const PoseFrame& f) {
  if (count_ > 0 && f.t_ns <= queued(count_ - 1).t_ns) return;
  const std::array<int64_t, kSegmentCount> ages_ns = sample_ages_ns(f);
  for (int s = 0; s < kSegmentCount; ++s) {
    const int64_t age_ns = ages_ns[s];
    // A key per new sample: a held orientation repeats the same sample time and is ignored.
    if (age_ns >= 0 && (f.segment_flags[s] & kSegTracked))
      tracks_[s].push(f.t_ns - age_ns, from_wxyz(f.q_earth_segment[s]));
  }
  if (count_ == ring_.size()) {
    std::vector<PoseFrame> grown(std::max<std::size_t>(64, 2 * ring_.size()));
    for (std::size_t i = 0; i < count_; ++i)
      grown[i] = queued(i);
    ring_.swap(grown);
    head_ = 0;
  }
  queued(count_++) = f;
}

bool DropoutBridge::next(PoseFrame& out) {
  if (count_ == 0) return false;
  if (!finished_ && queued(count_ - 1).t_ns - queued(0).t_ns < max_bridge_ns_) return false;
  out = queued(0);
  head_ = (head_ + 1) % ring_.size();
  --count_;
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  bool changed = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    q[s] = from_wxyz(out.q_earth_segment[s]);
    if (!(out.segment_flags[s] & kSegTracked)) continue;
    // Bridged: the frame falls between two of the segment's samples further apart than
    // nominal_gap_ns (and at most max_bridge_ns).
    if (!tracks_[s].bridged(out.t_ns, q[s])) continue;
    changed = true;
    ++bridged_;
  }
  if (changed) {
    const auto& p = out.p_earth_segment_m[0];
    pose_from_earth_orientations(dims_, q, Eigen::Vector3d(p[0], p[1], p[2]), out);
  }
  return true;
}

}  // namespace mocap
