// PrefetchSource: reads and decodes a SampleSource on a thread of its own, ahead of the consumer,
// in chunks of samples handed over through a small bounded queue. Offline replay then reads the
// file on one core while filters, skeleton and BVH run on the other. Order and content are
// unchanged, so replay stays bit-for-bit deterministic.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "mocap/daemon/replay.hpp"

namespace mocap::daemon {

class PrefetchSource final : public SampleSource {
 public:
  static constexpr std::size_t kChunk = 8192;  ///< samples per hand-over
  static constexpr std::size_t kAhead = 4;     ///< chunks read ahead at most

  explicit PrefetchSource(std::unique_ptr<SampleSource> inner);
  ~PrefetchSource() override;
  PrefetchSource(const PrefetchSource&) = delete;
  PrefetchSource& operator=(const PrefetchSource&) = delete;

  const Config& config() const override { return inner_->config(); }
  bool next(ImuSample& out) override;
  /// The reader's error, once next() has returned false.
  const std::string& error() const override { return error_; }
  double progress() const override { return progress_.load(std::memory_order_relaxed); }
  std::string calibration_text() const override { return calibration_text_; }
  /// The inner source's offset as it stood when the current chunk was read.
  bool unix_offset_ns(int64_t& out) const override {
    out = current_offset_ns_;
    return current_offset_known_;
  }

 private:
  void run();

  std::unique_ptr<SampleSource> inner_;
  std::string calibration_text_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::vector<ImuSample>> ready_;   // guarded by mu_
  std::deque<int64_t> ready_offsets_;          // guarded by mu_: unix offset per ready chunk
  bool offset_known_ = false;                  // set before the thread starts
  std::vector<std::vector<ImuSample>> spare_;  // guarded by mu_: emptied chunks for reuse
  bool done_ = false, stop_ = false;           // guarded by mu_
  std::string inner_error_;                    // guarded by mu_, set before done_
  std::vector<ImuSample> current_;             // consumer only
  std::size_t pos_ = 0;                        // consumer only
  int64_t current_offset_ns_ = 0;              // consumer only
  bool current_offset_known_ = false;          // consumer only
  std::string error_;                          // consumer only
  std::atomic<double> progress_{0};
  std::thread thread_;
};

}  // namespace mocap::daemon
