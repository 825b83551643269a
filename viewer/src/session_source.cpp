// Session playback: indexes the pose blocks of a session file, then reads the frame under the
// playback clock on demand (pause, seek, loop).
#include "mocap/viewer/session_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mocap::viewer {

double body_height_from_pose(const PoseFrame& f, double fallback_m) {
  const BodyDimensions unit = body_dimensions_from_height(1.0);
  double recorded = 0, reference = 0;
  for (int s = 1; s < kSegmentCount; ++s) {
    const int p = kSegmentParent[s];
    const auto& a = f.p_earth_segment_m[s];
    const auto& b = f.p_earth_segment_m[p];
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    recorded += std::sqrt(dx * dx + dy * dy + dz * dz);
    reference += unit.joint_offset_m[s].norm();
  }
  const double h = recorded / reference;
  return std::isfinite(h) && h > 0.5 && h < 3.0 ? h : fallback_m;
}

SessionSource::SessionSource(const std::string& path) {
  const auto slash = path.rfind('/');
  name_ = slash == std::string::npos ? path : path.substr(slash + 1);
  std::string error;
  if (!reader_.open(path, &error)) throw std::runtime_error("--play " + error);
  SessionReader::Block b;
  bool have_dims = false;
  while (reader_.next(b)) {
    if (b.type != session::BlockType::pose) continue;
    if (!index_.empty() && b.pose.t_ns < index_.back().t_ns) continue;  // never back in time
    index_.push_back({b.pose.t_ns, b.offset, b.inner});
    if (!have_dims) {
      dims_ = body_dimensions_from_height(body_height_from_pose(b.pose, 1.75));
      have_dims = true;
    }
  }
  if (index_.empty())
    throw std::runtime_error(
        "--play " + path + ": the session holds no pose frames" +
        (reader_.tail_reason().empty() ? std::string() : " (" + reader_.tail_reason() + ")") +
        "; a recording of samples only plays through the pipeline: mocapd --replay " + path +
        ", then mocap-viewer");
  if (reader_.end() != SessionReader::End::clean) tail_note_ = "  (ENDS EARLY: TORN OR DAMAGED)";
  duration_s_ = 1e-9 * static_cast<double>(index_.back().t_ns - index_.front().t_ns);
}

int SessionSource::frame_at(double position_s) const {
  const int n = frame_count();
  if (n == 1) return 0;
  // One frame interval past the last frame before looping, so the last frame is shown too.
  const double period = duration_s_ * n / (n - 1);
  double p = std::fmod(position_s, period);
  if (p < 0) p += period;
  const int64_t t = index_.front().t_ns + static_cast<int64_t>(std::llround(p * 1e9));
  const auto it = std::upper_bound(index_.begin(), index_.end(), t,
                                   [](int64_t v, const Entry& e) { return v < e.t_ns; });
  return static_cast<int>(std::max<std::ptrdiff_t>(0, (it - index_.begin()) - 1));
}

bool SessionSource::poll(double t_s, std::vector<PoseFrame>& frames) {
  const int k = frame_at(advance(t_s));
  if (k == shown_ && !frames.empty()) return false;
  SessionReader::Block b;
  if (!reader_.seek(index_[k].offset, index_[k].inner) || !reader_.next(b) ||
      b.type != session::BlockType::pose)
    return false;  // the file changed under us: keep showing the last frame
  frames.resize(1);
  frames[0] = b.pose;
  frames[0].flags |= kFrameReplay;
  frames[0].flags &= ~kFrameRecording;
  shown_ = k;
  return true;
}

std::string SessionSource::status() const {
  char s[200];
  const double t = 1e-9 * static_cast<double>(index_[std::max(shown_, 0)].t_ns - index_[0].t_ns);
  std::snprintf(s, sizeof s, "PLAYING %s  FRAME %d/%d  %.1f/%.1f S%s", name_.c_str(), shown_ + 1,
                frame_count(), t, duration_s_, tail_note_.c_str());
  return s;
}

}  // namespace mocap::viewer
