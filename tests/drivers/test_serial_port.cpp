// Serial transport on real pseudo-terminals: no data is not a hang-up, a hang-up is reported, a
// port held by another process is refused as busy (or the other reader is named), and a second
// reader on the same port does not become a reconnect storm.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <poll.h>

#include <atomic>
#include <cstdio>
#include <thread>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/devsim/sim_encoder.hpp"
#include "mocap/drivers/transport.hpp"

extern char** environ;

using namespace mocap;

namespace {

/// A child process that has `path` open as its stdin (and runs `prog`); killed on destruction.
class ChildHolding {
 public:
  ChildHolding(const std::string& path, std::vector<std::string> argv) {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, path.c_str(), O_RDONLY | O_NOCTTY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    std::vector<char*> args;
    for (auto& a : argv)
      args.push_back(a.data());
    args.push_back(nullptr);
    ok_ = posix_spawnp(&pid_, args[0], &fa, nullptr, args.data(), environ) == 0;
    posix_spawn_file_actions_destroy(&fa);
    // Wait until its stdin is the port (the open happens in the child).
    for (int i = 0; ok_ && i < 200; ++i) {
      char link[256];
      const std::string fd0 = "/proc/" + std::to_string(pid_) + "/fd/0";
      const ssize_t n = ::readlink(fd0.c_str(), link, sizeof link - 1);
      if (n > 0 && std::string(link, n).find("/dev/pts/") == 0) return;
      ::usleep(5000);
    }
  }
  ~ChildHolding() {
    if (!ok_) return;
    ::kill(pid_, SIGKILL);
    int st = 0;
    ::waitpid(pid_, &st, 0);
  }
  bool ok() const { return ok_; }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  bool ok_ = false;
};

}  // namespace

TEST(SerialPort, NoDataIsNotAHangUpAndAHangUpIs) {
  auto pty = std::make_unique<PtyEndpoint>();
  std::string err;
  auto t = open_serial({.port = pty->slave_path(), .baud = 115200}, err);
  ASSERT_TRUE(t) << err;
  std::array<uint8_t, 64> buf{};
  EXPECT_EQ(t->read(buf, 30, -1).kind, ReadResult::kTimeout);
  const uint8_t hello[] = {'h', 'i', '\n'};
  ASSERT_TRUE(pty->write(hello));
  ReadResult r = t->read(buf, 500, -1);
  ASSERT_EQ(r.kind, ReadResult::kData);
  EXPECT_EQ(r.n, 3u);
  EXPECT_EQ(t->read(buf, 30, -1).kind, ReadResult::kTimeout);
  pty.reset();  // the device's end closes
  r = t->read(buf, 500, -1);
  EXPECT_EQ(r.kind, ReadResult::kVanished);
  EXPECT_NE(r.reason.find("hang-up"), std::string::npos) << r.reason;
}

TEST(SerialPort, SecondOpenIsRefusedAsBusyAndFreedOnClose) {
  PtyEndpoint pty;
  std::string err;
  auto first = open_serial({.port = pty.slave_path()}, err);
  ASSERT_TRUE(first) << err;
  EXPECT_TRUE(first->warning().empty()) << first->warning();
  auto second = open_serial({.port = pty.slave_path()}, err);
  EXPECT_FALSE(second);
  EXPECT_NE(err.find("busy"), std::string::npos) << err;
  EXPECT_NE(err.find("another process"), std::string::npos) << err;
  EXPECT_NE(err.find(pty.slave_path()), std::string::npos) << err;
  first.reset();  // closing gives the port back (TIOCNXCL, flock released)
  auto again = open_serial({.port = pty.slave_path()}, err);
  EXPECT_TRUE(again) << err;
}

TEST(SerialPort, AnotherOpenerIsNamed) {
  PtyEndpoint pty;
  ChildHolding child(pty.slave_path(), {"sleep", "30"});
  ASSERT_TRUE(child.ok());
  std::string err;
  auto t = open_serial({.port = pty.slave_path()}, err);
  ASSERT_TRUE(t) << err;
  EXPECT_NE(t->warning().find(std::to_string(child.pid()) + " (sleep)"), std::string::npos)
      << t->warning();
}

// Issue 22: a second reader on the port made zero-byte reads that were taken as "device closed":
// 11-13 reconnects in 4 s. Now its stolen bytes are just missing data (naming another process:
// AnotherOpenerIsNamed).
TEST(E2eSerial, SecondReaderIsNoReconnectStorm) {
  SimOptions so{.protocol = "line", .rate_hz = 1000};
  SimulatedDevice sim(so);
  // A second reader on the same port (opened before the driver, as a forgotten terminal
  // program would be): it waits with poll and reads whatever it can, racing the driver.
  const int other = ::open(sim.path().c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(other, 0);
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> stolen{0};
  std::thread thief([&] {
    std::array<uint8_t, 256> b{};
    while (!stop) {
      pollfd p{other, POLLIN, 0};
      if (::poll(&p, 1, 50) > 0) {
        const ssize_t n = ::read(other, b.data(), b.size());
        if (n > 0) stolen += static_cast<std::size_t>(n);
      }
    }
  });
  sim.start();
  DeviceSpec spec{.name = "two", .protocol = "line", .port = sim.path()};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::error));
  test::CollectSink sink;
  dev->start(sink);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  dev->stop();
  sim.stop();
  stop = true;
  thief.join();
  ::close(other);
  const auto ev = sink.events_snapshot();
  ASSERT_FALSE(ev.empty());
  EXPECT_TRUE(ev.front().connected);
  // Silence may be reported when the other reader wins every race for 500 ms (it is right: no
  // data reached the driver); a vanish (hang-up, "device closed") must not be.
  int lost = 0;
  for (const auto& e : ev) {
    if (e.connected) continue;
    std::printf("disconnected: %s\n", e.reason.c_str());
    if (e.reason.rfind("no data for", 0) != 0) ++lost;
  }
  EXPECT_EQ(lost, 0);
  EXPECT_EQ(dev->stats().reconnects, 0u);
  std::printf(
      "two readers: %zu samples kept by the driver, %zu bytes taken by the other, %d "
      "disconnects\n",
      sink.count(), stolen.load(), lost);
}
