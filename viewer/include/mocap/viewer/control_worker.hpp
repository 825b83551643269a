// The window's link to a live daemon off the render thread: key requests ("calibrate npose")
// are queued and sent by one worker thread, which also asks for the daemon's status once a
// second for the HUD's calibration prompt. A daemon that accepts but never answers costs the
// worker its timeouts, never a frame.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

namespace mocap::viewer {

class ControlWorker {
 public:
  /// poll_status: fetch the calibration prompt every second. Timeouts: how long a request
  /// and a status poll wait for the daemon's reply.
  ControlWorker(std::string socket_path, bool poll_status, int request_timeout_ms = 500,
                int status_timeout_ms = 100);
  ~ControlWorker();
  ControlWorker(const ControlWorker&) = delete;
  ControlWorker& operator=(const ControlWorker&) = delete;

  /// Queues a request line; `what` names it in the outcome ("N-POSE CALIBRATION: OK").
  void request(std::string line, std::string what);
  /// The newest calibration prompt ("" when none, or no daemon answers).
  std::string prompt() const;
  /// The outcome of a request finished since the last call, if any.
  std::optional<std::string> take_message();

 private:
  void run();

  const std::string socket_path_;
  const bool poll_status_;
  const int request_timeout_ms_, status_timeout_ms_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::pair<std::string, std::string>> queue_;  ///< (line, what)
  std::string prompt_;
  std::optional<std::string> message_;
  bool stop_ = false;
  std::thread thread_;  ///< last: starts after the members it uses
};

}  // namespace mocap::viewer
