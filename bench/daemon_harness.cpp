// DaemonRig: ptys + WitMotion encoders (or SlimeVR boards on UDP) + a spawned mocapd; /proc
// readings (daemon_harness.hpp).
#include "daemon_harness.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/devsim/sim_slimevr.hpp"

namespace mocap::bench {

namespace {

/// n distinct free loopback ports (held open together while picked, so none repeats).
std::vector<int> free_ports(int type, int n) {
  std::vector<int> fds, ports;
  for (int i = 0; i < n; ++i) {
    const int fd = ::socket(AF_INET, type, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
      ports.push_back(ntohs(a.sin_port));
    if (fd >= 0) fds.push_back(fd);
  }
  for (const int fd : fds)
    ::close(fd);
  if (static_cast<int>(ports.size()) != n)
    throw std::runtime_error("cannot find a free loopback port");
  return ports;
}

int free_port(int type) {
  return free_ports(type, 1).front();
}

/// n distinct free UDP loopback ports below the kernel's ephemeral range, where no socket the
/// bench connects (those get ephemeral ports) can take one before mocapd binds it. Ports are
/// handed out once per process, from a per-process start.
std::vector<int> daemon_udp_ports(int n) {
  int low = 32768;
  if (std::ifstream r("/proc/sys/net/ipv4/ip_local_port_range"); r) r >> low;
  static int next = 0;
  if (next == 0) next = std::max(1024, low - 12000) + static_cast<int>(::getpid() % 4000);
  std::vector<int> fds, ports;
  while (static_cast<int>(ports.size()) < n && next < low) {
    const int port = next++;
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
      ports.push_back(port);
      fds.push_back(fd);
    } else if (fd >= 0) {
      ::close(fd);
    }
  }
  for (const int fd : fds)
    ::close(fd);
  if (static_cast<int>(ports.size()) != n)
    throw std::runtime_error("cannot find free UDP ports below the ephemeral range");
  return ports;
}

/// The MAC of simulated SlimeVR board i.
slimevr::Mac board_mac(int i) {
  return {0x02, 0x5E, 0x00, 0x00, static_cast<uint8_t>(i >> 8), static_cast<uint8_t>(i)};
}

/// A UDP socket connected to 127.0.0.1:port (a tracker board's).
int board_socket(int port) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0)
    throw std::runtime_error("cannot open a UDP socket for a SlimeVR board");
  return fd;
}

std::string mocapd_path() {
  const auto self = std::filesystem::read_symlink("/proc/self/exe");
  const auto p = self.parent_path() / "mocapd";
  if (!std::filesystem::exists(p))
    throw std::runtime_error("mocapd not found next to " + self.string());
  return p.string();
}

double status_field_mb(pid_t pid, const char* key) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  const size_t n = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, n, key) == 0) return std::atof(line.c_str() + n + 1) / 1024.0;
  return -1;
}

}  // namespace

DaemonRig::DaemonRig(const RigOptions& o) : opt_(o), start_ns_(monotonic_ns()) {
  char tmpl[] = "/tmp/mocap-bench-XXXXXX";
  if (!::mkdtemp(tmpl)) throw std::runtime_error("mkdtemp failed");
  dir_ = tmpl;
  ctl_ = dir_ + "/ctl.sock";
  log_ = dir_ + "/mocapd.log";
  port_ = free_port(SOCK_STREAM);
  const bool slime = opt_.protocol == "slimevr", line_udp = opt_.protocol == "line-udp";
  if (!slime && !line_udp && opt_.protocol != "witmotion")
    throw std::runtime_error("protocol " + opt_.protocol +
                             ": the harness has witmotion, slimevr, line-udp");
  const int udp_port = slime ? daemon_udp_ports(1).front() : 0;
  if (line_udp) udp_ports_ = daemon_udp_ports(opt_.sensors);
  std::ostringstream cfg;
  cfg << "[daemon]\nlog_level = \"warn\"\ncontrol_socket = \"" << ctl_ << "\"\n"
      << "[pipeline]\nrate_hz = " << opt_.frame_rate_hz
      << "\npublish_every_sample = " << (opt_.publish_every_sample ? "true" : "false")
      << "\nrealtime_priority = " << opt_.realtime_priority << "\n";
  if (opt_.read_batch_ms >= 0) cfg << "read_batch_ms = " << opt_.read_batch_ms << "\n";
  cfg << "[outputs.json]\nenabled = true\nport = " << port_ << "\n"
      << "[outputs.posture]\nenabled = false\n";
  EncoderOptions eo;
  eo.rate_hz = opt_.rate_hz;
  for (int i = 0; i < opt_.sensors; ++i) {
    if (slime) {
      boards_.push_back({board_socket(udp_port)});
      cfg << "[[sensor]]\nname = \"s" << i
          << "\"\ndriver = \"slimevr\"\nport = \"udp:127.0.0.1:" << udp_port
          << "\"\noptions = { mac = \"" << slimevr::mac_string(board_mac(i))
          << "\", tracker = 0 }\n";
    } else if (line_udp) {
      const int port = udp_ports_[static_cast<size_t>(i)];
      line_fds_.push_back(board_socket(port));
      enc_.push_back(make_encoder("line", eo));
      cfg << "[[sensor]]\nname = \"s" << i
          << "\"\ndriver = \"line\"\nport = \"udp:127.0.0.1:" << port << "\"\n";
    } else {
      ptys_.push_back(std::make_unique<PtyEndpoint>());
      enc_.push_back(make_encoder("witmotion", eo));
      cfg << "[[sensor]]\nname = \"s" << i << "\"\ndriver = \"witmotion\"\nport = \""
          << ptys_.back()->slave_path() << "\"\n";
    }
    if (i < kSegmentCount) cfg << "segment = \"" << kSegmentNames[i] << "\"\n";
  }
  const std::string cfg_path = dir_ + "/rig.toml";
  std::ofstream(cfg_path) << cfg.str();
  const std::string exe = mocapd_path();
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    ::execl(exe.c_str(), exe.c_str(), "--config", cfg_path.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  bytes_.reserve(256);
}

DaemonRig::~DaemonRig() {
  stop();
  for (const auto& b : boards_)
    ::close(b.fd);
  for (const int fd : line_fds_)
    ::close(fd);
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

int DaemonRig::stop() {
  if (pid_ > 0) {
    ::kill(pid_, SIGTERM);
    int st = 0;
    ::waitpid(pid_, &st, 0);
    exit_status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    pid_ = -1;
  }
  return exit_status_;
}

bool DaemonRig::write_sample(int i, int64_t t_device_ns, uint64_t* key) {
  if (!boards_.empty()) {
    SlimeBoard& b = boards_[static_cast<size_t>(i)];
    const double ph = t_device_ns * 1e-9;
    bytes_.clear();
    if (key) *key = b.number + 1;
    slime_sim::rotation(
        ++b.number, 0,
        Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * std::sin(ph), Eigen::Vector3d::UnitZ())),
        bytes_);
    return ::send(b.fd, bytes_.data(), bytes_.size(), MSG_DONTWAIT) ==
           static_cast<ssize_t>(bytes_.size());
  }
  ImuSample s;
  s.t_device_ns = t_device_ns;
  s.sensor_id = static_cast<uint16_t>(i);
  const double ph = t_device_ns * 1e-9;
  s.gyr_rad_s = Eigen::Vector3d(0.1 * std::sin(ph), 0.05, -0.02);
  s.acc_m_s2 = Eigen::Vector3d(0.1, -0.05, 9.81);
  s.mag_uT = Eigen::Vector3d(20, 0, -40);
  s.q_device_sensor = Eigen::Quaterniond::Identity();
  s.valid = kFieldGyr | kFieldAcc | kFieldMag | kFieldQuat;
  bytes_.clear();
  enc_[i]->encode(s, bytes_);
  if (key) *key = static_cast<uint64_t>(t_device_ns / 1'000'000 * 1'000'000);
  if (!line_fds_.empty())
    return ::send(line_fds_[static_cast<size_t>(i)], bytes_.data(), bytes_.size(), MSG_DONTWAIT) ==
           static_cast<ssize_t>(bytes_.size());
  return ptys_[i]->write(bytes_);
}

size_t DaemonRig::answer_host() {
  uint8_t buf[256];
  size_t host_bytes = 0;
  for (size_t i = 0; i < boards_.size(); ++i) {
    SlimeBoard& b = boards_[i];
    ssize_t n;
    while ((n = ::recv(b.fd, buf, sizeof buf, MSG_DONTWAIT)) > 0)
      if (n >= 11 && buf[0] == slimevr::kHandshake && std::memcmp(buf + 1, "Hey OVR =D", 10) == 0)
        b.answered = true;
    if (!b.answered) {
      bytes_.clear();
      slime_sim::handshake(board_mac(static_cast<int>(i)), bytes_);
      ::send(b.fd, bytes_.data(), bytes_.size(), MSG_DONTWAIT);
      b.number = 0;
    }
  }
  for (size_t i = 0; i < ptys_.size(); ++i) {
    const size_t n = ptys_[i]->read(std::span<uint8_t>(buf, sizeof buf), 0);
    if (n == 0) continue;
    host_bytes += n;
    reply_.clear();
    enc_[i]->handle_host_bytes(std::span<const uint8_t>(buf, n), reply_);
    if (!reply_.empty()) ptys_[i]->write(reply_);
  }
  return host_bytes;
}

std::string DaemonRig::status() const {
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", ctl_.c_str());
  std::string out;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::write(fd, "status\n", 7) == 7) {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) break;
      out.append(buf, static_cast<size_t>(n));
      if (out.back() == '\n') break;
    }
  }
  ::close(fd);
  return out;
}

bool DaemonRig::wait_streaming(double timeout_s) {
  const int64_t end = monotonic_ns() + static_cast<int64_t>(timeout_s * 1e9);
  int64_t last_host_ns = monotonic_ns();
  while (monotonic_ns() < end) {
    // Keep the sensors talking while the daemon opens and configures them.
    const int64_t t_dev = device_ns(monotonic_ns());
    for (int i = 0; i < opt_.sensors; ++i)
      write_sample(i, t_dev);
    if (answer_host() > 0) last_host_ns = monotonic_ns();
    const bool set_up = boards_.empty() ? monotonic_ns() - last_host_ns >= 300'000'000
                                        : std::all_of(boards_.begin(), boards_.end(),
                                                      [](const auto& b) { return b.answered; });
    const std::string st = set_up ? status() : std::string();
    if (!st.empty()) {
      size_t streaming = 0, pos = 0;
      while ((pos = st.find("\"streaming\"", pos)) != std::string::npos) {
        ++streaming;
        ++pos;
      }
      if (streaming == static_cast<size_t>(opt_.sensors)) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::string DaemonRig::log_tail() const {
  std::ifstream f(log_);
  std::string all((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return all.size() > 2000 ? all.substr(all.size() - 2000) : all;
}

int64_t DaemonRig::keep_alive(double seconds) {
  const int64_t start = monotonic_ns(), n = std::max<int64_t>(1, std::llround(seconds * 100));
  int64_t due = start;
  for (int64_t k = 0; k < n; ++k) {  // every 10 ms exactly, so the devices' period holds
    due = start + k * 10'000'000;
    const timespec ts{static_cast<time_t>(due / 1'000'000'000),
                      static_cast<long>(due % 1'000'000'000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    for (int i = 0; i < opt_.sensors; ++i)
      write_sample(i, device_ns(due));
    answer_host();
  }
  return due;
}

double process_cpu_s(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string s((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const auto rp = s.rfind(')');
  if (rp == std::string::npos) return -1;
  std::istringstream in(s.substr(rp + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  // Fields after the command: state(3) ... utime(14) stime(15).
  for (int k = 3; k <= 15 && in >> field; ++k) {
    if (k == 14) utime = std::stoull(field);
    if (k == 15) stime = std::stoull(field);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

double process_rss_mb(pid_t pid) {
  return status_field_mb(pid, "VmRSS:");
}
double process_hwm_mb(pid_t pid) {
  return status_field_mb(pid, "VmHWM:");
}

double thread_cpu_s() {
  rusage ru{};
  ::getrusage(RUSAGE_THREAD, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec +
         (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
}

double load_average_1m() {
  double l[3] = {0, 0, 0};
  return ::getloadavg(l, 3) > 0 ? l[0] : -1;
}

int connect_loopback(int port, double timeout_s) {
  const int64_t end = monotonic_ns() + static_cast<int64_t>(timeout_s * 1e9);
  while (monotonic_ns() < end) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
      int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      return fd;
    }
    ::close(fd);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return -1;
}

}  // namespace mocap::bench
