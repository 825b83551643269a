// Writes the calibration file off the pipeline thread. The pipeline hands over a copy of the
// calibration in use (fixed size, a short lock, no allocation); a worker thread writes it with
// save_calibration (temporary file + atomic rename). A newer calibration replaces one that is
// still waiting, so a slow disk costs stale files, never pipeline time.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "mocap/core/log.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::daemon {

class CalibrationSaver {
 public:
  /// Starts the writer thread. `log` (may be null) reports failed writes.
  CalibrationSaver(std::string path, Logger* log);
  /// Writes what is still waiting, then stops the thread.
  ~CalibrationSaver();
  CalibrationSaver(const CalibrationSaver&) = delete;
  CalibrationSaver& operator=(const CalibrationSaver&) = delete;

  /// Queues `c` for writing (replacing a calibration not yet written). Called by the pipeline.
  void offer(const Calibration& c);
  /// Blocks until every calibration offered before the call is on disk (or failed).
  void flush();
  /// Writes completed (successfully or not) so far.
  uint64_t writes() const;

 private:
  void run();

  const std::string path_;
  Logger* log_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  Calibration pending_;
  uint64_t offered_ = 0;  ///< number of offers so far
  uint64_t written_ = 0;  ///< offers covered by completed writes
  uint64_t writes_ = 0;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace mocap::daemon
