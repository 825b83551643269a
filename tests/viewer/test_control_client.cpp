// Control client against a real Unix-socket server: request line, replies, errors, timeouts.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <thread>

#include "../common/unix_listener.hpp"
#include "mocap/viewer/control_client.hpp"

namespace mocap::viewer {
namespace {

/// A one-connection server: reads one line into `request`, answers `reply` (if not empty).
class OneShotServer {
 public:
  explicit OneShotServer(std::string reply) : reply_(std::move(reply)) {
    path_ = "/tmp/mocap-viewer-ctl-" + std::to_string(getpid()) + ".sock";
    fd_ = test::listen_unix(path_, 1);
    thread_ = std::thread([this] {
      const int c = accept(fd_, nullptr, nullptr);
      if (c < 0) return;
      char ch;
      while (read(c, &ch, 1) == 1 && ch != '\n')
        request_ += ch;
      if (!reply_.empty())
        EXPECT_GT(write(c, reply_.data(), reply_.size()), 0);
      else
        usleep(400000);  // say nothing
      close(c);
    });
  }
  ~OneShotServer() {
    thread_.join();
    close(fd_);
    unlink(path_.c_str());
  }
  const std::string& path() const { return path_; }
  std::string request() {
    thread_.join();
    thread_ = std::thread([] {});
    return request_;
  }

 private:
  std::string reply_, path_, request_;
  int fd_ = -1;
  std::thread thread_;
};

TEST(ControlClient, SendsOneJsonLineAndReadsTheReply) {
  OneShotServer server("{\"ok\":true,\"message\":\"calibrating in 3 s\"}\n");
  const ControlReply r = send_control_request(server.path(), calibrate_request("npose"));
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.message, "calibrating in 3 s");
  EXPECT_EQ(server.request(), "calibrate npose");
}

TEST(ControlClient, DaemonErrorsAreReported) {
  OneShotServer server("{\"ok\":false,\"error\":\"no sensors streaming\"}\n");
  const ControlReply r = send_control_request(server.path(), heading_reset_request());
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.message, "no sensors streaming");
  EXPECT_EQ(server.request(), "reset-heading");
}

TEST(ControlClient, GarbageSilenceAndAbsenceAreErrors) {
  {
    OneShotServer server("this is not json\n");
    const ControlReply r = send_control_request(server.path(), heading_reset_request());
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.message.find("not JSON"), std::string::npos) << r.message;
  }
  {
    OneShotServer server("");
    const ControlReply r = send_control_request(server.path(), heading_reset_request(), 100);
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.message.find("did not answer within 100 ms"), std::string::npos) << r.message;
  }
  const ControlReply r = send_control_request("/nonexistent/mocapd.sock", heading_reset_request());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("/nonexistent/mocapd.sock"), std::string::npos) << r.message;
}

TEST(ControlClient, DefaultPathUsesXdgRuntimeDir) {
  setenv("XDG_RUNTIME_DIR", "/run/user/4242", 1);
  EXPECT_EQ(default_control_socket_path(), "/run/user/4242/mocapd.sock");
  unsetenv("XDG_RUNTIME_DIR");
  EXPECT_NE(default_control_socket_path().find("mocapd"), std::string::npos);
}

}  // namespace
}  // namespace mocap::viewer

namespace mocap::viewer {
namespace {

// The HUD's calibration prompt from a `status` reply (the daemon's JSON, as mocapd writes it).
TEST(ControlClient, CalibrationPromptSaysWhyACaptureWasRefused) {
  // Calibrated: nothing to say.
  EXPECT_EQ(calibration_prompt(R"({"ok":true,"calibrated":true,"calibration":{
      "message":"calibrated in npose, heading 1.2 deg"}})"),
            "");
  // A refused capture: its reason.
  EXPECT_EQ(calibration_prompt(R"J({"ok":true,"calibrated":false,"calibration":{
      "message":"refused: upper_arm_l moved 4.1 deg RMS (max 2)","refining":false}})J"),
            "CALIBRATION: REFUSED: UPPER_ARM_L MOVED 4.1 DEG RMS (MAX 2)");
  // Nothing yet, an older daemon, garbage.
  EXPECT_EQ(calibration_prompt(R"({"ok":true,"calibrated":false,"calibration":{"message":""}})"),
            "");
  EXPECT_EQ(calibration_prompt(R"({"ok":true,"calibrated":true})"), "");
  EXPECT_EQ(calibration_prompt("not json {"), "");
}

}  // namespace
}  // namespace mocap::viewer
