// Tests of the pose JSON stream: the line format parsed back with nlohmann::json, and the TCP
// server with real loopback clients (several readers, a stalled reader, an abusive sender).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "mocap/outputs/json_stream.hpp"

using mocap::PoseFrame;
using mocap::outputs::format_pose_json;
using mocap::outputs::PoseJsonServer;
using nlohmann::json;

namespace {

PoseFrame make_frame(uint64_t n) {
  PoseFrame f;
  mocap::reset_pose(f);
  f.frame = n;
  f.t_ns = 1'500'000'000 + static_cast<int64_t>(n) * 10'000'000;
  f.flags = mocap::kFrameCalibrated | mocap::kFrameRecording;
  for (int s = 0; s < mocap::kSegmentCount; ++s) {
    const float a = 0.01f * static_cast<float>(s) + 0.001f * static_cast<float>(n % 100);
    f.q_earth_segment[s] = {std::cos(a), std::sin(a), 0, 0};
    f.q_parent_segment[s] = {std::cos(a / 2), 0, std::sin(a / 2), 0};
    f.p_earth_segment_m[s] = {0.1f * static_cast<float>(s), -0.25f, 0.95f};
    f.joint_violation_deg[s] = static_cast<float>(s) * 0.5f;
    f.segment_flags[s] = mocap::kSegTracked | (s % 2 ? mocap::kSegAtRest : 0u);
  }
  f.sensor_count = 3;
  for (int i = 0; i < 3; ++i) {
    std::snprintf(f.sensors[i].name, sizeof f.sensors[i].name, "imu%d", i);
    f.sensors[i].segment = static_cast<int8_t>(i == 2 ? -1 : i);
    f.sensors[i].state = 2;
    f.sensors[i].rate_hz = 100.f;
    f.sensors[i].drops = static_cast<uint32_t>(i);
  }
  return f;
}

std::string format(const PoseFrame& f) {
  std::vector<char> buf(mocap::outputs::kPoseJsonMaxLine);
  const std::size_t n = format_pose_json(f, buf.data(), buf.size());
  return std::string(buf.data(), n);
}

/// A real TCP client on loopback that reads newline-delimited lines.
class LineClient {
 public:
  explicit LineClient(uint16_t port, int rcvbuf = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (rcvbuf > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~LineClient() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool connected() const { return connected_; }
  int fd() const { return fd_; }
  /// Reads whatever arrives within timeout_ms; false on EOF.
  bool pump(int timeout_ms) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return true;
    char buf[65536];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) return false;
    pending_.append(buf, static_cast<std::size_t>(n));
    std::size_t nl;
    while ((nl = pending_.find('\n')) != std::string::npos) {
      lines_.push_back(pending_.substr(0, nl));
      pending_.erase(0, nl + 1);
    }
    return true;
  }
  std::vector<std::string>& lines() { return lines_; }
  const std::string& pending() const { return pending_; }

 private:
  int fd_ = -1;
  bool connected_ = false;
  std::string pending_;
  std::vector<std::string> lines_;
};

template <typename Pred>
bool wait_until(Pred pred, int timeout_ms = 10000) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return pred();
}

void publish_paced(PoseJsonServer& server, const PoseFrame& f) {
  while (!server.publish(f))
    std::this_thread::sleep_for(std::chrono::microseconds(200));
}

}  // namespace

TEST(PoseJson, LineParsesBackWithTheDocumentedSchema) {
  const PoseFrame f = make_frame(42);
  const std::string line = format(f);
  ASSERT_FALSE(line.empty());
  EXPECT_EQ(line.back(), '\n');
  EXPECT_EQ(line.find('\n'), line.size() - 1);
  const json j = json::parse(line);
  EXPECT_EQ(j["v"], 1);
  EXPECT_EQ(j["frame"], 42);
  EXPECT_NEAR(j["t"].get<double>(), 1.92, 1e-9);
  EXPECT_EQ(j["t_ns"].get<int64_t>(), f.t_ns);
  EXPECT_TRUE(j["t_unix_ns"].is_null());  // no wall clock known: null, never a made-up time
  {
    PoseFrame g = f;
    g.t_unix_ns = 1'764'151'200'123'456'789;  // 2025-11-26 10:00:00.123456789 UTC
    const json k = json::parse(format(g));
    EXPECT_EQ(k["t_unix_ns"].get<int64_t>(), g.t_unix_ns);  // exact: an integer, not a double
  }
  EXPECT_EQ(j["flags"], mocap::kFrameCalibrated | mocap::kFrameRecording);
  ASSERT_EQ(j["segments"].size(), 16u);
  ASSERT_EQ(j["joints"].size(), 15u);
  ASSERT_EQ(j["sensors"].size(), 3u);
  for (int s = 0; s < mocap::kSegmentCount; ++s) {
    const json& seg = j["segments"][s];
    EXPECT_EQ(seg["name"], std::string(mocap::kSegmentNames[s]));
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(seg["q"][k].get<double>(), f.q_earth_segment[s][k], 1e-5);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(seg["p"][k].get<double>(), f.p_earth_segment_m[s][k], 1e-4);
    EXPECT_EQ(seg["flags"], f.segment_flags[s]);
  }
  for (int s = 1; s < mocap::kSegmentCount; ++s) {
    const json& jt = j["joints"][s - 1];
    EXPECT_EQ(jt["name"], std::string(mocap::kSegmentNames[s]));
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(jt["q"][k].get<double>(), f.q_parent_segment[s][k], 1e-5);
    EXPECT_NEAR(jt["violation_deg"].get<double>(), f.joint_violation_deg[s], 1e-2);
  }
  EXPECT_EQ(j["sensors"][0]["name"], "imu0");
  EXPECT_EQ(j["sensors"][1]["segment"], "torso");
  EXPECT_TRUE(j["sensors"][2]["segment"].is_null());
  EXPECT_EQ(j["sensors"][2]["drops"], 2);
  EXPECT_EQ(j["sensors"][0]["state"], 2);
}

TEST(PoseJson, NonFiniteAndHostileNamesStayValidJson) {
  PoseFrame f = make_frame(1);
  f.q_earth_segment[3][1] = std::numeric_limits<float>::quiet_NaN();
  f.p_earth_segment_m[0][2] = std::numeric_limits<float>::infinity();
  std::memcpy(f.sensors[0].name, "a\"b\\c\n\x01\xff", 9);
  f.sensors[0].segment = 99;  // out of range -> null
  const json j = json::parse(format(f));
  EXPECT_TRUE(j["segments"][3]["q"][1].is_null());
  EXPECT_TRUE(j["segments"][0]["p"][2].is_null());
  EXPECT_EQ(j["sensors"][0]["name"], "a\"b\\c\n\x01?");
  EXPECT_TRUE(j["sensors"][0]["segment"].is_null());
}

// UTF-8 sensor names (config files may hold them) reach the stream whole; broken, overlong,
// surrogate and truncated sequences still become '?'.
TEST(PoseJson, Utf8NamesAreKeptAndBrokenSequencesReplaced) {
  PoseFrame f = make_frame(1);
  std::snprintf(f.sensors[0].name, sizeof f.sensors[0].name, "Jos\xC3\xA9-\xE2\x82\xAC");
  std::snprintf(f.sensors[1].name, sizeof f.sensors[1].name, "a\xC3(\xC0\xAF\xED\xA0\x80z");
  std::memset(f.sensors[2].name, 'x', sizeof f.sensors[2].name);
  f.sensors[2].name[23] = '\xC3';  // a lead byte cut by the field's end
  const json j = json::parse(format(f));
  EXPECT_EQ(j["sensors"][0]["name"], "Jos\xC3\xA9-\xE2\x82\xAC");
  EXPECT_EQ(j["sensors"][1]["name"], "a?(?????z");
  EXPECT_EQ(j["sensors"][2]["name"], std::string(23, 'x') + "?");
}

TEST(PoseJson, FullRigFitsTheMaximumLineAndTooSmallBufferFailsCleanly) {
  PoseFrame f = make_frame(7);
  f.sensor_count = mocap::kMaxSensors;
  for (auto& s : f.sensors) {
    std::memset(s.name, '"', sizeof s.name - 1);  // worst case: every byte escaped
    s.rate_hz = 1e9f;
    s.last_age_ms = 1e9f;
    s.drops = s.errors = 0xffffffffu;
  }
  f.frame = std::numeric_limits<uint64_t>::max();
  f.t_ns = f.t_unix_ns = std::numeric_limits<int64_t>::min();
  for (auto& p : f.p_earth_segment_m)
    p = {-1e9f, -1e9f, -1e9f};
  const std::string line = format(f);
  ASSERT_FALSE(line.empty());
  EXPECT_TRUE(json::accept(line));
  std::vector<char> small(line.size() - 1);
  EXPECT_EQ(format_pose_json(f, small.data(), small.size()), 0u);
}

TEST(PoseJsonServer, SeveralClientsReceiveEveryFrameInOrder) {
  PoseJsonServer server;
  std::string err;
  PoseJsonServer::Options opt;
  opt.client_buffer_bytes = 4 << 20;  // holds every frame of the test: no skip is possible
  ASSERT_TRUE(server.start(opt, &err)) << err;
  ASSERT_NE(server.port(), 0);
  std::vector<std::unique_ptr<LineClient>> clients;
  for (int i = 0; i < 3; ++i) {
    clients.push_back(std::make_unique<LineClient>(server.port()));
    ASSERT_TRUE(clients.back()->connected());
  }
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_connected == 3; }));
  constexpr int kFrames = 200;
  std::thread publisher([&] {
    for (int n = 0; n < kFrames; ++n)
      publish_paced(server, make_frame(static_cast<uint64_t>(n)));
  });
  for (auto& c : clients) {
    ASSERT_TRUE(wait_until([&] {
      c->pump(5);
      return !c->lines().empty() && json::parse(c->lines().back())["frame"] == kFrames - 1;
    }));
  }
  publisher.join();
  for (auto& c : clients) {
    int64_t prev = -1;
    for (const auto& l : c->lines()) {
      const json j = json::parse(l);
      EXPECT_GT(j["frame"].get<int64_t>(), prev);
      prev = j["frame"].get<int64_t>();
    }
    // The buffers hold the whole test: nothing may be skipped.
    EXPECT_EQ(c->lines().size(), static_cast<std::size_t>(kFrames));
  }
  EXPECT_EQ(server.stats().frames_skipped, 0u);
  EXPECT_EQ(server.stats().frames_published, static_cast<uint64_t>(kFrames));
}

TEST(PoseJsonServer, StalledClientSkipsFramesWithoutStallingOthers) {
  PoseJsonServer server;
  std::string err;
  PoseJsonServer::Options opt;
  opt.client_buffer_bytes = 64 * 1024;
  ASSERT_TRUE(server.start(opt, &err)) << err;
  LineClient stalled(server.port(), 4096);
  LineClient reader(server.port());
  ASSERT_TRUE(stalled.connected() && reader.connected());
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_connected == 2; }));
  // ~8 KB per line: 3000 lines (24 MB) exceed every kernel and user buffer of the stalled one.
  // After them the publisher keeps sending until the reader has seen the last one (the reader
  // may itself skip frames on a loaded machine, the last one included).
  constexpr int kFrames = 3000;
  std::atomic<bool> seen_last{false};
  std::thread publisher([&] {
    for (uint64_t n = 0; !seen_last; ++n) {
      PoseFrame f = make_frame(n);
      f.sensor_count = mocap::kMaxSensors;
      publish_paced(server, f);
      if (n >= kFrames) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  const bool reached = wait_until(
      [&] {
        while (reader.pump(0) && !reader.lines().empty() &&
               json::parse(reader.lines().back())["frame"] < kFrames - 1) {
          pollfd p{reader.fd(), POLLIN, 0};
          if (::poll(&p, 1, 5) <= 0) break;
        }
        return !reader.lines().empty() &&
               json::parse(reader.lines().back())["frame"] >= kFrames - 1;
      },
      60000);
  seen_last = true;
  publisher.join();
  ASSERT_TRUE(reached);
  EXPECT_GT(server.stats().frames_skipped, 0u);
  // Now the stalled client reads what was queued for it: whole lines only, increasing, gaps.
  for (;;) {  // read until nothing more arrives for half a second
    pollfd p{stalled.fd(), POLLIN, 0};
    if (::poll(&p, 1, 500) <= 0 || !stalled.pump(0)) break;
  }
  ASSERT_FALSE(stalled.lines().empty());
  EXPECT_LT(stalled.lines().size(), static_cast<std::size_t>(kFrames));
  EXPECT_LT(stalled.lines().size(), reader.lines().size());
  int64_t prev = -1;
  for (const auto& l : stalled.lines()) {
    const json j = json::parse(l);  // throws on a half line
    EXPECT_GT(j["frame"].get<int64_t>(), prev);
    prev = j["frame"].get<int64_t>();
  }
}

TEST(PoseJsonServer, ClientSendingTooMuchIsDroppedOthersServed) {
  PoseJsonServer server;
  std::string err;
  ASSERT_TRUE(server.start({}, &err)) << err;
  LineClient abuser(server.port());
  LineClient good(server.port());
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_connected == 2; }));
  std::vector<char> junk(10000, 'x');
  ASSERT_EQ(::send(abuser.fd(), junk.data(), junk.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(junk.size()));
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_dropped == 1; }));
  EXPECT_TRUE(wait_until([&] { return !abuser.pump(10); }));  // EOF from the server
  publish_paced(server, make_frame(5));
  ASSERT_TRUE(wait_until([&] {
    good.pump(5);
    return !good.lines().empty();
  }));
  EXPECT_EQ(json::parse(good.lines()[0])["frame"], 5);
}

TEST(PoseJsonServer, ConnectionsBeyondTheLimitAreClosed) {
  PoseJsonServer server;
  std::string err;
  PoseJsonServer::Options opt;
  opt.max_clients = 2;
  ASSERT_TRUE(server.start(opt, &err)) << err;
  LineClient a(server.port()), b(server.port());
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_connected == 2; }));
  LineClient c(server.port());
  ASSERT_TRUE(wait_until([&] { return server.stats().clients_rejected == 1; }));
  EXPECT_TRUE(wait_until([&] { return !c.pump(10); }));
  EXPECT_EQ(server.stats().clients_connected, 2u);
}

TEST(PoseJsonServer, BadBindAddressGivesAClearError) {
  PoseJsonServer server;
  std::string err;
  PoseJsonServer::Options opt;
  opt.bind_address = "not-an-address";
  EXPECT_FALSE(server.start(opt, &err));
  EXPECT_NE(err.find("not-an-address"), std::string::npos) << err;
  PoseJsonServer first;
  ASSERT_TRUE(first.start({}, &err)) << err;
  opt.bind_address = "127.0.0.1";
  opt.port = first.port();
  EXPECT_FALSE(server.start(opt, &err));
  EXPECT_NE(err.find("cannot bind"), std::string::npos) << err;
  EXPECT_FALSE(server.publish(make_frame(1)));
}

// The private stream's Unix socket: created 0600, served like TCP, removed on stop; a regular
// file at the path is refused and left untouched, a live socket (another server) is refused, a
// stale one (its server gone) replaced, a relative path refused.
TEST(PoseJsonServer, UnixSocketIsPrivateAndNeverTakesAnotherFile) {
  char tmpl[] = "/tmp/mocap-json-unix-XXXXXX";
  ASSERT_NE(::mkdtemp(tmpl), nullptr);
  const std::string dir = tmpl, path = dir + "/pose.sock";
  std::string err;
  PoseJsonServer::Options opt;
  opt.unix_path = path;
  {
    PoseJsonServer server;
    ASSERT_TRUE(server.start(opt, &err)) << err;
    EXPECT_EQ(server.port(), 0);
    struct stat st {};
    ASSERT_EQ(::lstat(path.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
    EXPECT_EQ(st.st_mode & 0777, 0600u);
    // A client reads whole frames from it.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ASSERT_TRUE(wait_until([&] { return server.stats().clients_connected == 1; }));
    ASSERT_TRUE(server.publish(make_frame(5)));
    std::string got;
    char buf[4096];
    while (got.find('\n') == std::string::npos) {
      pollfd p{fd, POLLIN, 0};
      ASSERT_EQ(::poll(&p, 1, 5000), 1);
      const ssize_t n = ::read(fd, buf, sizeof buf);
      ASSERT_GT(n, 0);
      got.append(buf, static_cast<std::size_t>(n));
    }
    EXPECT_EQ(json::parse(got.substr(0, got.find('\n')))["frame"], 5);
    ::close(fd);
    // A second server on the same live socket is refused.
    PoseJsonServer second;
    EXPECT_FALSE(second.start(opt, &err));
    EXPECT_NE(err.find("another process is listening"), std::string::npos) << err;
  }
  struct stat st {};
  EXPECT_NE(::lstat(path.c_str(), &st), 0);  // removed by stop()

  // A stale socket (its server gone without removing it) is replaced.
  {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ::close(fd);
    PoseJsonServer server;
    EXPECT_TRUE(server.start(opt, &err)) << err;
  }
  // A regular file is refused and kept.
  {
    FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("precious", f);
    std::fclose(f);
    PoseJsonServer server;
    EXPECT_FALSE(server.start(opt, &err));
    EXPECT_NE(err.find("is not a socket"), std::string::npos) << err;
    EXPECT_NE(err.find(path), std::string::npos) << err;
    ASSERT_EQ(::lstat(path.c_str(), &st), 0);
    EXPECT_EQ(st.st_size, 8);
    ::unlink(path.c_str());
  }
  opt.unix_path = "relative.sock";
  PoseJsonServer server;
  EXPECT_FALSE(server.start(opt, &err));
  EXPECT_NE(err.find("not an absolute path"), std::string::npos) << err;
  ::rmdir(dir.c_str());
}
