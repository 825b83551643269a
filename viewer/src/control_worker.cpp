// The viewer's control requests and status polling on their own thread (control_worker.hpp).
#include "mocap/viewer/control_worker.hpp"

#include <chrono>

#include "mocap/viewer/control_client.hpp"

namespace mocap::viewer {

ControlWorker::ControlWorker(std::string socket_path, bool poll_status, int request_timeout_ms,
                             int status_timeout_ms)
    : socket_path_(std::move(socket_path)),
      poll_status_(poll_status),
      request_timeout_ms_(request_timeout_ms),
      status_timeout_ms_(status_timeout_ms),
      thread_([this] { run(); }) {}

ControlWorker::~ControlWorker() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void ControlWorker::request(std::string line, std::string what) {
  {
    std::lock_guard lock(m_);
    queue_.emplace_back(std::move(line), std::move(what));
  }
  cv_.notify_all();
}

std::string ControlWorker::prompt() const {
  std::lock_guard lock(m_);
  return prompt_;
}

std::optional<std::string> ControlWorker::take_message() {
  std::lock_guard lock(m_);
  return std::exchange(message_, std::nullopt);
}

void ControlWorker::run() {
  using clock = std::chrono::steady_clock;
  auto next_status = clock::now();
  std::unique_lock lock(m_);
  while (!stop_) {
    if (!queue_.empty()) {
      auto [line, what] = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      const ControlReply r = send_control_request(socket_path_, line, request_timeout_ms_);
      std::string outcome = what + ": " + (r.ok ? "OK" : "FAILED") +
                            (r.message.empty() || r.message == "ok" ? "" : " (" + r.message + ")");
      lock.lock();
      message_ = std::move(outcome);
      continue;
    }
    if (poll_status_ && clock::now() >= next_status) {
      lock.unlock();
      std::string p = fetch_calibration_prompt(socket_path_, status_timeout_ms_);
      lock.lock();
      prompt_ = std::move(p);
      next_status = clock::now() + std::chrono::seconds(1);
      continue;
    }
    if (poll_status_)
      cv_.wait_until(lock, next_status);
    else
      cv_.wait(lock);
  }
}

}  // namespace mocap::viewer
