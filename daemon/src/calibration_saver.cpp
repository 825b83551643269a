// Writer thread for the calibration file (see calibration_saver.hpp).
#include "mocap/daemon/calibration_saver.hpp"

#include <exception>

namespace mocap::daemon {

CalibrationSaver::CalibrationSaver(std::string path, Logger* log)
    : path_(std::move(path)), log_(log), thread_([this] { run(); }) {}

CalibrationSaver::~CalibrationSaver() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void CalibrationSaver::offer(const Calibration& c) {
  {
    std::lock_guard lock(mu_);
    pending_ = c;
    ++offered_;
  }
  cv_.notify_all();
}

void CalibrationSaver::flush() {
  std::unique_lock lock(mu_);
  const uint64_t target = offered_;
  cv_.wait(lock, [&] { return written_ >= target; });
}

uint64_t CalibrationSaver::writes() const {
  std::lock_guard lock(mu_);
  return writes_;
}

void CalibrationSaver::run() {
  std::unique_lock lock(mu_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || written_ < offered_; });
    if (written_ >= offered_) return;  // stopping with nothing left to write
    const Calibration c = pending_;
    const uint64_t covers = offered_;
    lock.unlock();
    try {
      save_calibration(c, path_);
    } catch (const std::exception& e) {
      if (log_) log_->error("cannot save calibration: %s", e.what());
    }
    lock.lock();
    written_ = covers;
    ++writes_;
    cv_.notify_all();
  }
}

}  // namespace mocap::daemon
