// Shared-posture source: opens the segment when it appears, copies the newest frame.
#include "mocap/viewer/shm_source.hpp"

#include <stdexcept>

namespace mocap::viewer {

ShmSource::ShmSource(std::string name) : name_(std::move(name)) {}

bool ShmSource::poll(double t_s, std::vector<PoseFrame>& frames) {
  if (!reader_) {
    if (t_s < next_try_s_) return false;
    next_try_s_ = t_s + 0.5;
    try {
      reader_ = std::make_unique<outputs::PostureReader>(name_);
      error_.clear();
    } catch (const std::exception& e) {
      error_ = e.what();
      return false;
    }
  }
  if (paused_) return false;
  const uint64_t seq = reader_->sequence();
  if (seq == last_sequence_ && !frames.empty()) {
    // Silent for 2 s: the daemon may have restarted with a new segment under the same name, so
    // map it again (harmless if it is only idle).
    if (t_s - last_change_s_ > 2.0) {
      reader_.reset();
      last_change_s_ = t_s;
    }
    return false;
  }
  last_change_s_ = t_s;
  PoseFrame f;
  if (!reader_->read(f)) return false;
  last_sequence_ = seq;
  frames.resize(1);
  frames[0] = f;
  return true;
}

std::string ShmSource::status() const {
  if (!reader_) return "WAITING FOR MOCAPD (" + name_ + ")";
  return "SHARED POSTURE " + name_;
}

}  // namespace mocap::viewer
