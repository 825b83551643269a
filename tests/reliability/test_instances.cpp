// One mocapd per runtime directory, private runtime files, and a mocapctl that trusts only its
// own user's daemon (issue 20, item 4), against the real binaries: a second instance says
// "already running (pid N)", exits non-zero and changes nothing (the first one's shared posture
// and control socket survive); two daemons never share a posture; a crash leaves no stale lock;
// without XDG_RUNTIME_DIR the runtime directory is private (lstat-checked); a control socket
// served by another user is refused (SO_PEERCRED).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>
#include <csignal>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "harness.hpp"
#include "mocap/core/runtime_dir.hpp"
#include "mocap/daemon/control.hpp"

using namespace mocap;
using namespace mocap::reliability;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

/// Runs mocapd with a config to completion (it is expected to refuse to start).
int run_mocapd(const TempDir& dir, const std::string& name, const std::string& config,
               std::string& out) {
  const std::string cfg = dir.file(name + ".toml");
  { std::ofstream(cfg) << config; }
  const Result r = run_bin("mocapd", {"--config", cfg}, 20);
  out = r.err + r.out;
  return r.code;
}

std::string posture_config(const std::string& shm) {
  return "[outputs.posture]\nenabled = true\nshm_name = \"" + shm + "\"\n";
}

/// base_config with the posture turned on under `shm` (base_config turns it off).
std::string config_with_posture(const TempDir& dir, int port, const std::string& shm) {
  std::string c = base_config(dir, port);
  const std::string off = "[outputs.posture]\nenabled = false\n";
  c.replace(c.find(off), off.size(), posture_config(shm));
  return c;
}

}  // namespace

TEST(Instances, ASecondInstanceSaysAlreadyRunningAndChangesNothing) {
  TempDir dir;
  TwoSensorRig rig(dir);
  const std::string shm = "/mocap-test-" + std::to_string(::getpid()) + "-inst";
  const std::string cfg = config_with_posture(dir, free_tcp_port(), shm) + rig.sensors_toml();
  Daemon a(dir, "first", cfg);
  ASSERT_TRUE(a.wait_ready(15s)) << a.log_text();
  ASSERT_TRUE(fs::exists("/dev/shm" + shm));
  ASSERT_TRUE(wait_until([&] { return a.status().value("frame", 0ull) > 0; }, 15s));
  const auto before = a.status();
  std::string out;
  const int code = run_mocapd(dir, "second", cfg, out);
  EXPECT_NE(code, 0) << out;
  EXPECT_NE(out.find("already running (pid " + std::to_string(a.pid()) + ")"), std::string::npos)
      << out;
  // Nothing of the first daemon changed: its shared posture, socket and sensors are there.
  EXPECT_TRUE(fs::exists("/dev/shm" + shm));
  EXPECT_TRUE(fs::exists(a.socket()));
  EXPECT_TRUE(a.status().value("ok", false));
  EXPECT_TRUE(wait_until(
      [&] { return a.status().value("frame", 0ull) > before.value("frame", 0ull); }, 10s));
  EXPECT_EQ(out.find("shared posture"), std::string::npos) << out;  // it created nothing
  EXPECT_EQ(a.quit(), 0) << a.log_text();
  EXPECT_FALSE(fs::exists("/dev/shm" + shm));  // removed by its creator on exit
}

TEST(Instances, TwoDaemonsNeverShareOnePostureAndACrashLeavesNoStaleLock) {
  TempDir dir, other;
  TwoSensorRig rig(dir);
  const std::string shm = "/mocap-test-" + std::to_string(::getpid()) + "-shared";
  Daemon a(dir, "a", config_with_posture(dir, free_tcp_port(), shm) + rig.sensors_toml());
  ASSERT_TRUE(a.wait_ready(15s)) << a.log_text();
  // Another runtime directory (its own control socket), the same posture name, no sensors
  // of its own worth opening: refused before it publishes; the first one's posture survives.
  std::string out;
  const int code = run_mocapd(other, "b",
                              config_with_posture(other, free_tcp_port(), shm) +
                                  line_sensor_toml("c", other.file("none"), "pelvis"),
                              out);
  EXPECT_NE(code, 0) << out;
  EXPECT_NE(out.find("in use by another mocapd"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists("/dev/shm" + shm));
  EXPECT_TRUE(a.status().value("ok", false));
  // kill -9: the kernel drops the lock; the next daemon starts at once.
  a.kill9();
  Daemon c(dir, "c", config_with_posture(dir, free_tcp_port(), shm) + rig.sensors_toml());
  EXPECT_TRUE(c.wait_ready(15s)) << c.log_text();
  EXPECT_EQ(c.quit(), 0) << c.log_text();
}

TEST(Instances, WithoutXdgRuntimeDirTheRuntimeDirectoryIsPrivate) {
  TempDir base, home;
  const char* saved = std::getenv("XDG_RUNTIME_DIR");
  const std::string saved_value = saved ? saved : "";
  ::unsetenv("XDG_RUNTIME_DIR");
  const std::string mine = base.path() + "/mocapd-" + std::to_string(::geteuid());
  const std::string fallback = home.path() + "/.cache/mocapd";
  std::string err;
  // Fresh: created 0700 and used.
  EXPECT_EQ(private_runtime_dir(&err, base.path().c_str(), home.path().c_str()), mine) << err;
  struct stat st {};
  ASSERT_EQ(::lstat(mine.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  EXPECT_EQ(st.st_uid, ::geteuid());
  // Taken first by someone else (a symlink, a directory others can write): never used.
  fs::remove(mine);
  ASSERT_EQ(::symlink(home.path().c_str(), mine.c_str()), 0);
  EXPECT_EQ(private_runtime_dir(&err, base.path().c_str(), home.path().c_str()), fallback);
  fs::remove(mine);
  ASSERT_EQ(::mkdir(mine.c_str(), 0777), 0);
  ASSERT_EQ(::chmod(mine.c_str(), 0777), 0);
  EXPECT_EQ(private_runtime_dir(&err, base.path().c_str(), home.path().c_str()), fallback);
  if (::geteuid() == 0) {  // owned by another user
    ASSERT_EQ(::chmod(mine.c_str(), 0700), 0);
    ASSERT_EQ(::chown(mine.c_str(), 65534, 65534), 0);
    std::string why;
    EXPECT_FALSE(ensure_private_dir(mine, &why));
    EXPECT_NE(why.find("owned by uid 65534"), std::string::npos) << why;
  }
  // Nowhere private: an error, never a shared path.
  fs::remove(fallback);
  ASSERT_EQ(::symlink("/tmp", fallback.c_str()), 0);
  EXPECT_EQ(private_runtime_dir(&err, base.path().c_str(), home.path().c_str()), "");
  EXPECT_NE(err.find("XDG_RUNTIME_DIR"), std::string::npos) << err;
  if (!saved_value.empty()) ::setenv("XDG_RUNTIME_DIR", saved_value.c_str(), 1);
}

TEST(Instances, MocapctlRefusesAControlSocketServedByAnotherUser) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run a fake daemon as another user";
  TempDir dir;
  ASSERT_EQ(::chmod(dir.path().c_str(), 0777), 0);
  const std::string sock = dir.file("impostor.sock");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {  // the impostor: another user answering {"ok":true} to anything
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(3);
    ::signal(SIGPIPE, SIG_IGN);
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, sock.c_str(), sizeof a.sun_path - 1);
    if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(fd, 4) != 0)
      ::_exit(4);
    ::chmod(sock.c_str(), 0777);
    (void)!::write(ready[1], "x", 1);
    for (;;) {
      const int c = ::accept(fd, nullptr, nullptr);
      if (c < 0) ::_exit(5);
      char buf[256];
      (void)!::read(c, buf, sizeof buf);
      (void)!::write(c, "{\"ok\":true}\n", 12);
      ::close(c);
    }
  }
  char x;
  ASSERT_EQ(::read(ready[0], &x, 1), 1);
  try {
    daemon::control_call(sock, "record stop", 2000);
    ADD_FAILURE() << "the impostor's reply was trusted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("uid 65534"), std::string::npos) << e.what();
  }
  // mocapctl itself exits non-zero and says why.
  const Result ctl = run_bin("mocapctl", {"--socket", sock, "status"});
  EXPECT_TRUE(ctl.code > 0 && ctl.code < 128) << ctl.code;
  EXPECT_NE((ctl.err + ctl.out).find("not by us"), std::string::npos) << ctl.err << ctl.out;
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
}

TEST(Instances, ASharedPostureCreatedByAnotherUserIsRefused) {
  TempDir dir;
  const std::string shm = "/mocap-test-" + std::to_string(::getpid()) + "-foreign";
  const std::string path = "/dev/shm" + shm;
  {  // "another user" prepared it world-readable (as root we can also give it away)
    std::ofstream(path) << "";
    ASSERT_EQ(::chmod(path.c_str(), 0666), 0);
    if (::geteuid() == 0) {
      ASSERT_EQ(::chown(path.c_str(), 65534, 65534), 0);
    }
  }
  std::string out;
  const int code = run_mocapd(dir, "foreign",
                              config_with_posture(dir, free_tcp_port(), shm) +
                                  line_sensor_toml("c", dir.file("none"), "pelvis"),
                              out);
  EXPECT_NE(code, 0) << out;
  EXPECT_NE(out.find("is not private to us"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(path));  // left untouched
  fs::remove(path);
}
