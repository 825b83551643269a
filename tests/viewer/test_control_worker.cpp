// The viewer's ControlWorker against a real Unix-socket server that holds its reply until the
// test releases it (reply timeouts of 10 s, so a loaded machine cannot time them out): a key's
// request returns before the daemon answers (the render thread never waits on it), the outcome
// arrives afterwards, and the status poll fills the calibration prompt from the daemon's status
// replies.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

#include "../common/unix_listener.hpp"
#include "mocap/viewer/control_worker.hpp"

namespace mocap::viewer {
namespace {

/// Serves connections one after another: reads one line, records it, then answers `reply` once
/// the test has released it (release() also lets every later connection through).
class GatedServer {
 public:
  explicit GatedServer(std::string reply) : reply_(std::move(reply)) {
    path_ = "/tmp/mocap-viewer-worker-" + std::to_string(getpid()) + ".sock";
    fd_ = test::listen_unix(path_, 4);
    thread_ = std::thread([this] {
      for (;;) {
        const int c = accept(fd_, nullptr, nullptr);
        if (c < 0) return;  // shut down
        std::string line;
        char ch;
        while (read(c, &ch, 1) == 1 && ch != '\n')
          line += ch;
        std::unique_lock lock(m_);
        requests_.push_back(line);
        cv_.notify_all();
        cv_.wait(lock, [&] { return released_; });
        lock.unlock();
        EXPECT_GT(write(c, reply_.data(), reply_.size()), 0);
        close(c);
      }
    });
  }
  ~GatedServer() {
    release();
    shutdown(fd_, SHUT_RDWR);
    thread_.join();
    close(fd_);
    unlink(path_.c_str());
  }
  const std::string& path() const { return path_; }
  /// Waits (up to 10 s) until `n` requests arrived; returns the n-th.
  std::string wait_for_request(size_t n) {
    std::unique_lock lock(m_);
    cv_.wait_for(lock, std::chrono::seconds(10), [&] { return requests_.size() >= n; });
    return requests_.size() >= n ? requests_[n - 1] : "";
  }
  void release() {
    std::lock_guard lock(m_);
    released_ = true;
    cv_.notify_all();
  }

 private:
  std::string reply_, path_;
  int fd_ = -1;
  std::mutex m_;
  std::condition_variable cv_;
  std::vector<std::string> requests_;
  bool released_ = false;
  std::thread thread_;
};

/// Polls f() every 10 ms for up to 10 s until its value is non-empty.
template <typename F>
auto wait_for(F f) {
  for (int i = 0; i < 1000; ++i) {
    auto v = f();
    if (!(v == decltype(v){})) return v;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return f();
}

TEST(ControlWorker, RequestReturnsBeforeTheDaemonAnswers) {
  GatedServer server("{\"ok\":true}\n");
  ControlWorker worker(server.path(), false, 10000, 10000);
  worker.request("calibrate npose", "N-POSE CALIBRATION");
  // The daemon has the request and holds its answer; this thread is already here.
  EXPECT_EQ(server.wait_for_request(1), "calibrate npose");
  EXPECT_FALSE(worker.take_message());
  server.release();
  const auto m = wait_for([&] { return worker.take_message(); });
  ASSERT_TRUE(m);
  EXPECT_EQ(*m, "N-POSE CALIBRATION: OK");
  EXPECT_FALSE(worker.take_message());  // taken once
}

TEST(ControlWorker, StatusPollFillsTheCalibrationPrompt) {
  // One line: the worker reads the reply up to its newline.
  GatedServer server(R"J({"ok":true,"calibrated":false,"calibration":{)J"
                     R"J("message":"refused: pelvis moved 3 deg RMS (max 2)","refining":false}})J"
                     "\n");
  ControlWorker worker(server.path(), true, 10000, 10000);
  EXPECT_EQ(server.wait_for_request(1), "status");
  EXPECT_EQ(worker.prompt(), "");  // still waiting for the reply
  server.release();
  const std::string p = wait_for([&] { return worker.prompt(); });
  EXPECT_EQ(p, "CALIBRATION: REFUSED: PELVIS MOVED 3 DEG RMS (MAX 2)");
  EXPECT_EQ(server.wait_for_request(2), "status");  // asked again a second later
}

TEST(ControlWorker, AbsentDaemonIsAFailedOutcome) {
  ControlWorker worker("/nonexistent/mocapd.sock", true);
  worker.request("reset-heading", "HEADING RESET");
  const auto m = wait_for([&] { return worker.take_message(); });
  ASSERT_TRUE(m);
  EXPECT_NE(m->find("HEADING RESET: FAILED (cannot reach mocapd at /nonexistent/mocapd.sock"),
            std::string::npos)
      << *m;
  EXPECT_EQ(worker.prompt(), "");
}

}  // namespace
}  // namespace mocap::viewer
