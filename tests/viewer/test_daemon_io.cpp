// The viewer against the daemon's real servers: its control client speaks to the control
// socket server, its --connect source reads the pose JSON stream server.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "mocap/daemon/control.hpp"
#include "mocap/outputs/json_stream.hpp"
#include "mocap/viewer/control_client.hpp"
#include "mocap/viewer/net_source.hpp"
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {
namespace {

TEST(ViewerWithDaemon, CalibrationAndHeadingResetReachTheControlServer) {
  LogSink sink;
  const std::string path = "/tmp/mocap-viewer-daemon-" + std::to_string(getpid()) + ".sock";
  std::vector<daemon::ControlRequest> seen;
  daemon::ControlServer server(
      path,
      [&](const daemon::ControlRequest& r) {
        seen.push_back(r);
        if (r.command == daemon::ControlCommand::reset_heading)
          return daemon::control_error_reply("no sensors streaming");
        return std::string("{\"ok\":true,\"message\":\"calibration (") + r.argument + ") in 3 s\"}";
      },
      Logger(sink, "test", LogLevel::warn));
  const ControlReply t = send_control_request(path, calibrate_request("tpose"), 2000);
  EXPECT_TRUE(t.ok) << t.message;
  EXPECT_EQ(t.message, "calibration (tpose) in 3 s");
  const ControlReply h = send_control_request(path, heading_reset_request(), 2000);
  EXPECT_FALSE(h.ok);
  EXPECT_EQ(h.message, "no sensors streaming");
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].command, daemon::ControlCommand::calibrate);
  EXPECT_EQ(seen[0].argument, "tpose");
  EXPECT_EQ(seen[1].command, daemon::ControlCommand::reset_heading);
}

TEST(ViewerWithDaemon, ConnectSourceShowsTheStreamedPose) {
  outputs::PoseJsonServer server;
  std::string err;
  ASSERT_TRUE(server.start({}, &err)) << err;
  NetSource src("127.0.0.1:" + std::to_string(server.port()));

  const BodyDimensions dims = body_dimensions_from_height(1.75);
  PoseFrame sent = reference_pose(dims, Eigen::Vector3f(1.5f, -0.5f, 0));
  sent.flags = kFrameCalibrated | kFrameRecording;
  sent.segment_flags[5] = kSegTracked | kSegLimitViolated;
  sent.joint_violation_deg[5] = 9.25f;
  sent.sensor_count = 1;
  std::snprintf(sent.sensors[0].name, sizeof sent.sensors[0].name, "wrist-imu");
  sent.sensors[0].segment = 6;
  sent.sensors[0].state = 2;

  std::vector<PoseFrame> frames;
  const auto start = std::chrono::steady_clock::now();
  auto t_s = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  uint64_t n = 0;
  while (t_s() < 10) {
    sent.frame = ++n;
    server.publish(sent);  // connected clients get frames from the next one on
    if (src.poll(t_s(), frames)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(frames.size(), 1u) << src.status();
  const PoseFrame& got = frames[0];
  EXPECT_GE(got.frame, 1u);
  EXPECT_EQ(got.flags, sent.flags);
  for (int s = 0; s < kSegmentCount; ++s) {
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(got.p_earth_segment_m[s][k], sent.p_earth_segment_m[s][k], 1e-4);
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(got.q_earth_segment[s][k], sent.q_earth_segment[s][k], 1e-5);
  }
  EXPECT_EQ(got.segment_flags[5], sent.segment_flags[5]);
  EXPECT_NEAR(got.joint_violation_deg[5], 9.25f, 0.01f);
  EXPECT_STREQ(got.sensors[0].name, "wrist-imu");
  EXPECT_EQ(got.sensors[0].segment, 6);
  EXPECT_EQ(src.bad_lines(), 0u);
  EXPECT_NE(src.status().find("CONNECTED"), std::string::npos);

  server.stop();  // the viewer notices and reports it
  for (int i = 0; i < 100 && src.status().find("closed") == std::string::npos; ++i) {
    src.poll(t_s(), frames);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_NE(src.status().find("closed"), std::string::npos) << src.status();
}

TEST(ViewerWithDaemon, ConnectSourceReportsRefusedConnections) {
  NetSource src("127.0.0.1:1");
  std::vector<PoseFrame> frames;
  for (int i = 0; i < 50 && src.status().find('(') == std::string::npos; ++i) {
    EXPECT_FALSE(src.poll(0.01 * i, frames));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_NE(src.status().find("refused"), std::string::npos) << src.status();
  EXPECT_THROW(NetSource("nohostport"), std::runtime_error);
  EXPECT_THROW(NetSource("host:99999"), std::runtime_error);
}

}  // namespace
}  // namespace mocap::viewer
