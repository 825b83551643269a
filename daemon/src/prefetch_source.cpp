// Read-ahead thread for offline replay (see prefetch_source.hpp).
#include "mocap/daemon/prefetch_source.hpp"

namespace mocap::daemon {

PrefetchSource::PrefetchSource(std::unique_ptr<SampleSource> inner)
    : inner_(std::move(inner)), calibration_text_(inner_->calibration_text()) {
  int64_t unused = 0;
  offset_known_ = inner_->unix_offset_ns(unused);
  thread_ = std::thread([this] { run(); });
}

PrefetchSource::~PrefetchSource() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void PrefetchSource::run() {
  for (;;) {
    std::vector<ImuSample> chunk;
    {
      std::unique_lock lock(mu_);
      cv_.wait(lock, [&] { return stop_ || ready_.size() < kAhead; });
      if (stop_) return;
      if (!spare_.empty()) {
        chunk = std::move(spare_.back());
        spare_.pop_back();
      }
    }
    chunk.resize(kChunk);
    std::size_t n = 0;
    while (n < kChunk && inner_->next(chunk[n]))
      ++n;
    chunk.resize(n);
    int64_t offset = 0;
    inner_->unix_offset_ns(offset);
    progress_.store(inner_->progress(), std::memory_order_relaxed);
    const bool end = n < kChunk;
    {
      std::lock_guard lock(mu_);
      if (n > 0) {
        ready_.push_back(std::move(chunk));
        ready_offsets_.push_back(offset);
      }
      if (end) {
        inner_error_ = inner_->error();
        done_ = true;
      }
    }
    cv_.notify_all();
    if (end) return;
  }
}

bool PrefetchSource::next(ImuSample& out) {
  if (pos_ == current_.size()) {
    std::unique_lock lock(mu_);
    if (!current_.empty()) spare_.push_back(std::move(current_));
    cv_.notify_all();
    cv_.wait(lock, [&] { return !ready_.empty() || done_; });
    if (ready_.empty()) {
      error_ = inner_error_;
      current_.clear();
      pos_ = 0;
      return false;
    }
    current_ = std::move(ready_.front());
    ready_.pop_front();
    current_offset_ns_ = ready_offsets_.front();
    ready_offsets_.pop_front();
    current_offset_known_ = offset_known_;
    pos_ = 0;
    cv_.notify_all();
  }
  out = current_[pos_++];
  return true;
}

}  // namespace mocap::daemon
