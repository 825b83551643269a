// An offline frame sink on a thread of its own (see frame_writer_thread.hpp).
#include "mocap/outputs/frame_writer_thread.hpp"

namespace mocap::outputs {

FrameWriterThread::FrameWriterThread(Output& target) : target_(target) {
  current_.reserve(kChunk);
  thread_ = std::thread([this] { run(); });
}

FrameWriterThread::~FrameWriterThread() {
  try {
    finish();
  } catch (...) {
  }
}

void FrameWriterThread::on_frame(const PoseFrame& frame) {
  current_.push_back(frame);
  if (current_.size() == kChunk) hand_over();
}

void FrameWriterThread::hand_over() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [&] { return ready_.size() < kAhead || error_; });
  if (error_) {  // the writer stopped: keep nothing more (finish() reports it)
    current_.clear();
    return;
  }
  ready_.push_back(std::move(current_));
  if (!spare_.empty()) {
    current_ = std::move(spare_.back());
    spare_.pop_back();
  } else {
    current_ = {};
    current_.reserve(kChunk);
  }
  cv_.notify_all();
}

void FrameWriterThread::finish() {
  if (!thread_.joinable()) return;
  if (!current_.empty()) hand_over();
  {
    std::lock_guard lock(mu_);
    closing_ = true;
  }
  cv_.notify_all();
  thread_.join();
  if (error_) std::rethrow_exception(error_);
}

void FrameWriterThread::run() {
  for (;;) {
    std::vector<PoseFrame> chunk;
    {
      std::unique_lock lock(mu_);
      cv_.wait(lock, [&] { return !ready_.empty() || closing_; });
      if (ready_.empty()) return;  // closing and all written
      chunk = std::move(ready_.front());
      ready_.pop_front();
    }
    cv_.notify_all();
    try {
      for (const PoseFrame& f : chunk)
        target_.on_frame(f);
    } catch (...) {
      std::lock_guard lock(mu_);
      error_ = std::current_exception();
      ready_.clear();
      cv_.notify_all();
      return;
    }
    chunk.clear();
    std::lock_guard lock(mu_);
    spare_.push_back(std::move(chunk));
  }
}

}  // namespace mocap::outputs
