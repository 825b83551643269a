// Clients against the real mocapd: many JSON-stream clients at once, a client that never
// reads, clients connecting and dropping in a loop, malformed and oversized control requests,
// and the control socket refused to another user. The pipeline must lose no frames, other
// clients keep receiving, the daemon keeps answering status. Rates and latencies are printed as
// measured figures, never asserted.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "../common/raw_unix_call.hpp"
#include "harness.hpp"

using namespace mocap::reliability;
using namespace std::chrono_literals;

TEST(Clients, ManyStreamClientsASilentOneAndAChurningLoopLoseNoFrames) {
  TwoSensorDaemon setup("clients", {"--set", "outputs.json.max_clients=128"});
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();

  // 100 readers at once, one client that never reads, and a thread connecting and dropping
  // clients in a loop (beyond the limit of 128 they are refused, which is fine).
  std::vector<std::unique_ptr<StreamClient>> clients;
  for (int i = 0; i < 100; ++i)
    clients.push_back(std::make_unique<StreamClient>(port));
  StreamClient silent(port, /*read=*/false);
  std::atomic<bool> churn_stop{false};
  std::atomic<int> churned{0};
  std::thread churn([&] {
    while (!churn_stop) {
      StreamClient c(port, /*read=*/false);
      ++churned;
      std::this_thread::sleep_for(5ms);
    }
  });
  const auto st0 = d.status();
  std::this_thread::sleep_for(3s);
  const auto st1 = d.status();
  churn_stop = true;
  churn.join();

  const uint64_t frames = st1.value("frame", 0ull) - st0.value("frame", 0ull);
  int served = 0;
  uint64_t gaps = 0, bad = 0;
  std::vector<double> lat;
  int clients_with_gaps = 0;
  for (auto& c : clients) {
    if (c->lines() > 0) ++served;
    gaps += c->frame_gaps();
    if (c->frame_gaps() > 0) ++clients_with_gaps;
    bad += c->bad_lines();
    auto l = c->latencies_ms();
    lat.insert(lat.end(), l.begin(), l.end());
  }
  // The pipeline lost nothing, every reader was served and still receives, the daemon answers.
  // Frames the stream skipped for a reader (I/O thread starved on a loaded machine) are
  // reported as a figure, not asserted.
  EXPECT_EQ(st1.value("ring_drops", 1ull), 0u) << st1.dump();
  EXPECT_GT(frames, 100u);
  EXPECT_EQ(served, 100);
  EXPECT_EQ(bad, 0u);
  std::vector<uint64_t> seen;
  for (auto& c : clients)
    seen.push_back(c->lines());
  // Every reader keeps receiving (given time: under ThreadSanitizer 100 reader threads on 2
  // cores take seconds to catch up).
  const bool all_advance = wait_until(
      [&] {
        for (size_t i = 0; i < clients.size(); ++i)
          if (clients[i]->lines() <= seen[i]) return false;
        return true;
      },
      10s);
  EXPECT_TRUE(all_advance);
  if (!all_advance) {
    for (size_t i = 0; i < clients.size(); ++i) {
      EXPECT_GT(clients[i]->lines(), seen[i]) << "client " << i << " stopped receiving";
    }
  }
  EXPECT_TRUE(d.status().value("ok", false));
  std::printf(
      "[figures] 100 stream clients + 1 silent + %d churned connections over 3 s: "
      "%d clients served, %.1f frames/s published, latency p50 %.2f ms p99 %.2f ms "
      "max %.2f ms, %llu frames skipped in %d clients\n",
      churned.load(), served, frames / 3.0, percentile(lat, 50), percentile(lat, 99),
      percentile(lat, 100), static_cast<unsigned long long>(gaps), clients_with_gaps);
  clients.clear();
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Clients, MalformedAndOversizedControlRequestsGetErrorsAndTheDaemonCarriesOn) {
  TwoSensorDaemon setup("control");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  StreamClient watcher(port);

  const std::vector<std::string> bad{
      "",
      "\n",
      "bogus\n",
      "status extra\n",
      "calibrate sideways\n",
      "record\n",
      std::string("sta\0tus\n", 8),
      "status\x01\n",
      std::string(5000, 'A') + "\n",
      std::string(1 << 20, 'x'),  // 1 MiB without a newline
      "\xff\xfe\xfd\n",
  };
  int errors = 0;
  for (const auto& req : bad) {
    const std::string reply = mocap::test::raw_unix_call(d.socket(), req);
    if (reply.empty()) continue;  // closing without a reply is acceptable for garbage
    const auto j = nlohmann::json::parse(reply, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << "reply is not JSON: " << reply.substr(0, 200);
    EXPECT_FALSE(j.value("ok", true)) << reply;
    EXPECT_FALSE(j.value("error", "").empty()) << reply;
    ++errors;
  }
  EXPECT_GE(errors, 8);
  // A client that connects and sends nothing must not block the next one for long.
  const int idle = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::strncpy(a.sun_path, d.socket().c_str(), sizeof a.sun_path - 1);
  ASSERT_EQ(::connect(idle, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json st;
  EXPECT_NO_THROW(st = d.call("status", 15000));
  const double blocked_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ::close(idle);
  EXPECT_TRUE(st.value("ok", false));
  EXPECT_EQ(st.value("ring_drops", 1ull), 0u);
  // (No longer 2 s behind a silent client, the test may get here before the first frame.)
  EXPECT_TRUE(wait_until([&] { return watcher.lines() > 0; }, 10s));
  EXPECT_EQ(watcher.frame_gaps(), 0u);
  std::printf(
      "[figures] %zu malformed/oversized requests: %d error replies; a silent control "
      "client delayed the next status by %.2f s\n",
      bad.size(), errors, blocked_s);
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Clients, ControlSocketIsClosedToOtherUsers) {
  TempDir dir;
  ASSERT_EQ(::chmod(dir.path().c_str(), 0755), 0);  // the directory itself does not protect it
  TwoSensorRig rig(dir);
  Daemon d(dir, "perm", base_config(dir, free_tcp_port()) + rig.sensors_toml());
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  struct stat sb {};
  ASSERT_EQ(::stat(d.socket().c_str(), &sb), 0);
  EXPECT_EQ(sb.st_mode & 0777, 0600u);
  EXPECT_EQ(sb.st_uid, ::geteuid());
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to switch to another user";
  // Another user (nobody) tries to connect: refused by the kernel.
  EXPECT_EQ(connect_unix_as_nobody(d.socket()), 0)
      << "1 = another user connected, 2 = unexpected errno, 3 = not nobody, -1 = died";
  EXPECT_TRUE(d.status().value("ok", false));
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

namespace {

/// CPU time (user + system) the process has used, in seconds.
double cpu_seconds(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(f, line);
  std::istringstream s(line.substr(line.rfind(')') + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  for (int i = 3; i <= 15; ++i) {
    s >> field;
    if (i == 14) utime = std::stoull(field);
    if (i == 15) stime = std::stoull(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

int connect_tcp(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  (void)::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);  // EINPROGRESS is fine
  return fd;
}

}  // namespace

TEST(Clients, SilentControlClientsDelayNobody) {
  TwoSensorDaemon setup("silentctl");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  std::vector<int> idle;
  for (int i = 0; i < 3; ++i) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, d.socket().c_str(), sizeof a.sun_path - 1);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    idle.push_back(fd);
  }
  // 1.5 s is less than the 2 s the former one-at-a-time server spent on each silent client.
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json start, stop;
  ASSERT_NO_THROW(start = d.call("record start late.mocapses", 1500)) << d.log_text();
  EXPECT_TRUE(start.value("ok", false)) << start.dump();
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_NO_THROW(stop = d.call("record stop", 1500));
  EXPECT_TRUE(stop.value("ok", false)) << stop.dump();
  for (int fd : idle)
    ::close(fd);
  std::printf("[figures] 3 silent control clients: record start answered after %.3f s\n", waited);
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Clients, FdExhaustionNeitherSpinsNorSilencesControl) {
  TwoSensorDaemon setup("fds", {"--set", "outputs.json.max_clients=1000"});
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  // Leave the daemon 40 more descriptors than it has, then connect 120 stream clients. The count
  // is read once: the daemon's threads open and close descriptors, and two reads that differ
  // would ask for a soft limit above the hard one (EINVAL; seen once in CI under ASan).
  const auto fds_plus_40 = static_cast<rlim_t>(d.fd_count() + 40);
  const rlimit lim{fds_plus_40, fds_plus_40};
  ASSERT_EQ(::prlimit(d.pid(), RLIMIT_NOFILE, &lim, nullptr), 0) << std::strerror(errno);
  std::vector<int> socks;
  for (int i = 0; i < 120; ++i)
    socks.push_back(connect_tcp(port));
  std::this_thread::sleep_for(500ms);
  const double c0 = cpu_seconds(d.pid());
  std::this_thread::sleep_for(2s);
  const double cpu_share = (cpu_seconds(d.pid()) - c0) / 2.0;
  // Control still answers while every descriptor is taken (the reserve fd takes its place).
  nlohmann::json st;
  EXPECT_NO_THROW(st = d.call("status", 5000)) << d.log_text();
  EXPECT_TRUE(st.value("ok", false));
  for (int fd : socks)
    ::close(fd);
  // Once the clients leave, new ones are served. A client that connects before the server has
  // seen the closes is still shed (taken on the reserve fd and closed, as when full): it
  // connects again (failed once in CI under ASan when the first connection was shed).
  std::unique_ptr<StreamClient> reader;
  EXPECT_TRUE(wait_until(
      [&] {
        reader = std::make_unique<StreamClient>(port);
        return wait_until([&] { return reader->lines() > 0; }, 300ms);
      },
      10s))
      << d.call("status", 5000).dump() << d.log_text();
  std::printf(
      "[figures] fd limit reached with 120 stream clients: daemon CPU %.0f %% of a core; "
      "status answered\n",
      cpu_share * 100);
  // A busy loop on the readable listener took a whole core (108 % before the fix).
  EXPECT_LT(cpu_share, 0.8);
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Clients, StreamClientsThatNeverReadAreEvictedFirstWhenFull) {
  TwoSensorDaemon setup("evict", {"--set", "outputs.json.max_clients=4"});
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  // The server is full of clients that never read.
  std::vector<std::unique_ptr<StreamClient>> idle;
  for (int i = 0; i < 4; ++i)
    idle.push_back(std::make_unique<StreamClient>(port, /*read=*/false));
  // A reader gets in once those have stalled (their kernel buffers and queues full).
  std::unique_ptr<StreamClient> reader;
  const auto t0 = std::chrono::steady_clock::now();
  const bool served = wait_until(
      [&] {
        if (!reader || !reader->connected()) reader = std::make_unique<StreamClient>(port);
        if (wait_until([&] { return reader->lines() > 0; }, 300ms)) return true;
        reader.reset();
        return false;
      },
      30s);
  EXPECT_TRUE(served) << "a reading client never got in past the stalled ones";
  std::printf(
      "[figures] 4 non-reading stream clients filled max_clients=4: a reader was served "
      "after %.1f s\n",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}
