// The outputs' registry: make_outputs() builds the enabled outputs in the table's order from their
// options, each frame reaches each of them (the shared posture read back, a VMC bundle received
// on a real UDP socket, the JSON stream listening), and an output that cannot start stops the
// whole start with an error naming its section.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>
#include <string>

#include "mocap/outputs/json_stream.hpp"
#include "mocap/outputs/posture_shm.hpp"
#include "mocap/outputs/registry.hpp"

namespace mocap::outputs {
namespace {

std::string unique_shm_name(const char* what) {
  return "/mocap-test-registry-" + std::string(what) + "-" + std::to_string(::getpid());
}

OutputsConfig nothing_enabled() {
  OutputsConfig c;
  c.json.enabled = c.vmc.enabled = c.vrchat.enabled = c.posture.enabled = false;
  return c;
}

/// A UDP socket on a free loopback port.
struct UdpReceiver {
  int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  int port = 0;
  UdpReceiver() {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0)
      throw std::runtime_error("udp receiver");
    port = ntohs(a.sin_port);
  }
  ~UdpReceiver() { ::close(fd); }
  /// The first datagram within 5 s ("" if none).
  std::string receive() const {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 5000) != 1) return {};
    char buf[2048];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }
};

PoseFrame frame_number(uint64_t n) {
  PoseFrame f;
  reset_pose(f);
  f.frame = n;
  f.t_ns = static_cast<int64_t>(n) * 10'000'000;
  return f;
}

TEST(Registry, EveryRowIsAnOutputsSectionOnce) {
  ASSERT_GE(output_rows().size(), 4u);
  for (std::size_t i = 0; i < output_rows().size(); ++i) {
    const OutputRow& r = output_rows()[i];
    EXPECT_EQ(r.section, "outputs." + std::string(r.name));
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_NE(output_rows()[j].name, r.name);
  }
  EXPECT_TRUE(make_outputs(nothing_enabled(), {}).empty());
}

TEST(Registry, TheEnabledOutputsAreBuiltInOrderAndEachGetsTheFrames) {
  OutputsConfig c = nothing_enabled();
  c.posture.enabled = true;
  c.posture.shm_name = unique_shm_name("frames");
  c.json.enabled = true;
  c.json.port = 0;  // any free port
  UdpReceiver vmc;
  c.vmc.enabled = true;
  c.vmc.port = vmc.port;
  auto outs = make_outputs(c, {});
  ASSERT_EQ(outs.size(), 3u);  // posture, json, vmc: the table's order
  EXPECT_EQ(dynamic_cast<PoseJsonServer*>(outs[0].get()), nullptr);
  EXPECT_NE(dynamic_cast<PoseJsonServer*>(outs[1].get()), nullptr);
  EXPECT_GT(json_stream_port(outs), 0);

  for (auto& o : outs)
    o->on_frame(frame_number(42));
  PostureReader reader(c.posture.shm_name);
  PoseFrame back;
  ASSERT_TRUE(reader.read(back));
  EXPECT_EQ(back.frame, 42u);
  const std::string datagram = vmc.receive();
  ASSERT_FALSE(datagram.empty());
  EXPECT_EQ(datagram.compare(0, 8, std::string("#bundle\0", 8)), 0);
}

TEST(Registry, AnOutputThatCannotStartNamesItsSection) {
  OutputsConfig c = nothing_enabled();
  c.json.enabled = true;
  c.json.bind = "256.0.0.1";
  try {
    make_outputs(c, {});
    FAIL() << "a bad bind address started";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("outputs.json: ", 0), 0u) << e.what();
  }
  // A second publisher of one shared posture is refused, the first one keeps it.
  OutputsConfig p = nothing_enabled();
  p.posture.enabled = true;
  p.posture.shm_name = unique_shm_name("twice");
  auto first = make_outputs(p, {});
  ASSERT_EQ(first.size(), 1u);
  try {
    make_outputs(p, {});
    FAIL() << "a second posture output started";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("outputs.posture: ", 0), 0u) << m;
    EXPECT_NE(m.find("in use"), std::string::npos) << m;
  }
  first[0]->on_frame(frame_number(7));
  PoseFrame back;
  ASSERT_TRUE(PostureReader(p.posture.shm_name).read(back));
  EXPECT_EQ(back.frame, 7u);
}

}  // namespace
}  // namespace mocap::outputs
