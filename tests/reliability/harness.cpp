// Implementation of the reliability harness: child-process mocapd, pty line sensors, stream
// clients (see harness.hpp).
#include "harness.hpp"

#include "../common/free_port.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "mocap/core/time.hpp"
#include "mocap/daemon/control.hpp"
#include "mocap/drivers/line_protocol.hpp"

namespace fs = std::filesystem;

namespace mocap::reliability {

TempDir::TempDir() {
  std::string tmpl = "/tmp/mocap-rel-XXXXXX";
  if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
  path_ = tmpl;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

int free_tcp_port() {
  return test::free_loopback_port(SOCK_STREAM);
}

int free_udp_port() {
  return test::free_loopback_port(SOCK_DGRAM);
}

bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (pred()) return true;
    if (std::chrono::steady_clock::now() > end) return pred();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// ---- line sensor on a pty ----

LineSensorPty::LineSensorPty(std::string link_path)
    : link_(std::move(link_path)), pty_(std::make_unique<PtyEndpoint>(link_)) {}

bool LineSensorPty::write_sample(uint64_t t_us, double phase) {
  // A slowly turning, level sensor: gravity on z (in g), a small rotation about z (dps), a
  // horizontal field (uT) turning with it.
  const double yaw = 0.3 * std::sin(phase);
  const std::array<double, 9> v{
      0.0,  0.0, 1.0, 0.0, 0.0, 17.0 * std::cos(phase), 20.0 * std::cos(yaw), -20.0 * std::sin(yaw),
      -40.0};
  const std::string line = line::format_line(t_us, v, true);
  return write_bytes(line);
}

bool LineSensorPty::write_bytes(const std::string& bytes) {
  std::lock_guard lock(mu_);  // the feeder thread writes while the test unplugs
  if (!pty_) return false;
  return pty_->write({reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()});
}

void LineSensorPty::vanish() {
  std::lock_guard lock(mu_);
  pty_.reset();
}

void LineSensorPty::reappear() {
  std::lock_guard lock(mu_);
  if (!pty_) pty_ = std::make_unique<PtyEndpoint>(link_);
}

// ---- fault-injecting feeder ----

LineFeeder::LineFeeder(std::vector<Sensor*> sensors) : sensors_(std::move(sensors)) {
  thread_ = std::thread([this] { run(); });
}

LineFeeder::~LineFeeder() {
  stop_ = true;
  thread_.join();
}

void LineFeeder::jump(size_t i, int64_t dt_us) {
  std::lock_guard lock(mu_);
  sensors_[i]->t_us = static_cast<uint64_t>(static_cast<int64_t>(sensors_[i]->t_us) + dt_us);
}

void LineFeeder::run() {
  std::mt19937 rng(7);
  auto next = std::chrono::steady_clock::now();
  double phase = 0;
  while (!stop_) {
    next += std::chrono::milliseconds(10);
    phase += 0.05;
    {
      std::lock_guard lock(mu_);
      for (Sensor* s : sensors_) {
        const FaultMode m = s->mode.load();
        if (m == FaultMode::silent) {
          s->t_us += 10000;
          continue;
        }
        if (m == FaultMode::garbage) {
          std::string junk(1 + rng() % 40, '\0');
          for (char& ch : junk)
            ch = static_cast<char>(rng() % 256);
          s->pty->write_bytes(junk);
        }
        if (m == FaultMode::wrong_baud) {
          // What a 9600-baud stream read at 115200 looks like: no line structure at all.
          std::string junk(60, '\0');
          for (char& ch : junk)
            ch = static_cast<char>(0x80 | (rng() % 128));
          s->pty->write_bytes(junk);
          s->t_us += 10000;
          continue;
        }
        if (m == FaultMode::glitch && ++s->ticks % 10 == 0) {
          s->pty->write_bytes(
              line::format_line(s->t_us & s->wrap_mask, {0, 0, 1, 5000, 0, 0, 20, 0, -40}, true));
          s->t_us += 10000;
          ++s->written;
          continue;
        }
        // Every other tick a line cut off mid-number: it runs into the next line (both lost).
        if (m == FaultMode::truncated && (++s->ticks & 1))
          s->pty->write_bytes("123456 0.01 0.02 0.9");
        const int n = m == FaultMode::flood ? 10 : 1;
        for (int k = 0; k < n; ++k) {
          s->pty->write_sample(s->t_us & s->wrap_mask, phase + 0.005 * k);
          s->t_us += static_cast<uint64_t>(10000 / n);
          ++s->written;
        }
      }
    }
    std::this_thread::sleep_until(next);
  }
}

TwoSensorRig::TwoSensorRig(const TempDir& dir)
    : a(dir.file("a")),
      b(dir.file("b")),
      fa{&a, 0xffffffffull, 0},
      fb{&b, 0xffffffffull, 0},
      feeder({&fa, &fb}) {}

std::string TwoSensorRig::sensors_toml() const {
  return line_sensor_toml("a", a.link(), "pelvis") + line_sensor_toml("b", b.link(), "torso");
}

// ---- mocapd child process ----

Daemon::Daemon(const TempDir& dir, std::string name, const std::string& config_toml,
               std::vector<std::string> extra_args) {
  const std::string cfg = dir.file(name + ".toml");
  {
    std::ofstream f(cfg);
    f << config_toml;
  }
  socket_ = dir.file("ctl.sock");
  log_ = dir.file(name + ".log");
  const std::string exe = std::string(MOCAP_BINARY_DIR) + "/bin/mocapd";
  std::vector<std::string> args{exe, "--config", cfg};
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  // Everything the child needs is prepared before fork(): other threads (feeders) are running,
  // so the child may only make async-signal-safe calls until execv.
  std::vector<char*> argv;
  for (auto& a : args)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  const int log_fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot create " + log_);
  pid_ = ::fork();
  if (pid_ < 0) {
    ::close(log_fd);
    throw std::runtime_error("fork failed");
  }
  if (pid_ == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::dup2(log_fd, 2);
    ::dup2(log_fd, 1);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(log_fd);
}

Daemon::~Daemon() {
  if (!reaped_) kill9();
}

std::string Daemon::log_text() const {
  return slurp_file(log_);
}

nlohmann::json Daemon::call(const std::string& line, int timeout_ms) const {
  return nlohmann::json::parse(daemon::control_call(socket_, line, timeout_ms));
}

bool Daemon::running() {
  if (reaped_) return false;
  int st = 0;
  if (::waitpid(pid_, &st, WNOHANG) == pid_) {
    reaped_ = true;
    return false;
  }
  return true;
}

bool Daemon::wait_ready(std::chrono::milliseconds timeout) {
  return wait_until(
             [&] {
               if (!running()) return true;
               try {
                 return status().value("ok", false);
               } catch (const std::exception&) {
                 return false;
               }
             },
             timeout) &&
         running();
}

int Daemon::kill9() {
  if (reaped_) return 0;
  ::kill(pid_, SIGKILL);
  int st = 0;
  ::waitpid(pid_, &st, 0);
  reaped_ = true;
  return st;
}

int Daemon::quit(std::chrono::milliseconds timeout) {
  if (reaped_) return -1;
  try {
    call("quit");
  } catch (const std::exception&) {
    ::kill(pid_, SIGTERM);
  }
  int st = 0;
  const bool exited = wait_until([&] { return ::waitpid(pid_, &st, WNOHANG) == pid_; }, timeout);
  if (!exited) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &st, 0);
    reaped_ = true;
    return -2;
  }
  reaped_ = true;
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

long Daemon::rss_kb() const {
  std::ifstream f("/proc/" + std::to_string(pid_) + "/status");
  std::string key;
  while (f >> key) {
    if (key == "VmRSS:") {
      long kb = 0;
      f >> kb;
      return kb;
    }
  }
  return -1;
}

int Daemon::fd_count() const {
  std::error_code ec;
  int n = 0;
  for (auto it = fs::directory_iterator("/proc/" + std::to_string(pid_) + "/fd", ec);
       !ec && it != fs::directory_iterator(); ++it)
    ++n;
  return n;
}

std::string base_config(const TempDir& dir, int json_port, const std::string& extra) {
  std::ostringstream c;
  c << "[daemon]\nlog_level = \"info\"\ncontrol_socket = \"" << dir.file("ctl.sock") << "\"\n"
    << "[pipeline]\nrate_hz = 120\n"
    << "[outputs.json]\nenabled = true\nbind = \"127.0.0.1\"\nport = " << json_port << "\n"
    << "[outputs.vmc]\nenabled = false\n"
    << "[outputs.posture]\nenabled = false\n"
    << "[recording]\ndirectory = \"" << dir.path() << "\"\n"
    << extra;
  return c.str();
}

std::string line_sensor_toml(const std::string& name, const std::string& port,
                             const std::string& segment, const std::string& units) {
  std::ostringstream c;
  c << "[[sensor]]\nname = \"" << name << "\"\ndriver = \"line\"\nport = \"" << port
    << "\"\nsegment = \"" << segment << "\"\n";
  if (!units.empty()) c << "[sensor.options]\nunits = \"" << units << "\"\n";
  return c.str();
}

nlohmann::json sensor_status(const nlohmann::json& status, const std::string& name) {
  for (const auto& s : status.at("sensors"))
    if (s.value("name", std::string()) == name) return s;
  return nlohmann::json::object();  // not listed yet (before the first frame)
}

bool both_streaming(Daemon& d) {
  const auto st = d.status();
  return sensor_status(st, "a").value("state", "") == "streaming" &&
         sensor_status(st, "b").value("state", "") == "streaming";
}

TwoSensorDaemon::TwoSensorDaemon(const std::string& name, std::vector<std::string> extra_args,
                                 const std::string& extra_config)
    : rig(dir),
      json_port(free_tcp_port()),
      d(dir, name, base_config(dir, json_port, extra_config) + rig.sensors_toml(),
        std::move(extra_args)) {}

bool TwoSensorDaemon::ready_and_streaming() {
  using namespace std::chrono_literals;
  return d.wait_ready(15s) && wait_until([&] { return both_streaming(d); }, 15s);
}

Result run_bin(const std::string& program, const std::vector<std::string>& args, int timeout_s) {
  std::vector<std::string> argv;
  if (timeout_s > 0) argv = {"/usr/bin/timeout", std::to_string(timeout_s)};
  argv.push_back(std::string(MOCAP_BINARY_DIR) + "/bin/" + program);
  argv.insert(argv.end(), args.begin(), args.end());
  return run(std::move(argv));
}

int connect_unix_as_nobody(const std::string& path) {
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(3);
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::strncpy(a.sun_path, path.c_str(), sizeof a.sun_path - 1);
    const int rc = ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::_exit(rc == 0 ? 1 : (errno == EACCES ? 0 : 2));
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// ---- JSON stream client ----

namespace {

/// The number after `"key":` at the top level of a frame line (the schema puts "frame" and "t"
/// before any nested object). False if absent or not a number.
template <class T>
bool top_level_number(std::string_view line, std::string_view key, T& out) {
  const std::string pattern = "\"" + std::string(key) + "\":";
  const std::size_t at = line.find(pattern);
  const std::size_t nested = line.find_first_of("[{", 1);
  if (at == std::string_view::npos || (nested != std::string_view::npos && at > nested))
    return false;
  const char* b = line.data() + at + pattern.size();
  const auto r = std::from_chars(b, line.data() + line.size(), out);
  return r.ec == std::errc();
}

}  // namespace

struct StreamClient::State {
  std::atomic<bool> stop{false};
  mutable std::mutex mu;
  uint64_t lines = 0, bad = 0, gaps = 0;
  int64_t last_frame = -1;
  std::vector<double> latencies_ms;
  std::thread thread;
};

StreamClient::StreamClient(int port, bool read) : st_(std::make_shared<State>()) {
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<uint16_t>(port));
  if (::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd_);
    fd_ = -1;
    return;
  }
  if (!read) return;
  st_->thread = std::thread([fd = fd_, st = st_] {
    std::string buf;
    char chunk[16384];
    while (!st->stop.load()) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
      if (n <= 0) break;
      const double now_s = ns_to_s(monotonic_ns());
      buf.append(chunk, static_cast<size_t>(n));
      size_t start = 0, nl;
      while ((nl = buf.find('\n', start)) != std::string::npos) {
        const std::string_view line(buf.data() + start, nl - start);
        start = nl + 1;
        // Validated as JSON without building a document, frame and time read in place: with
        // 100 client threads a DOM per line (dozens of allocations) made the test crawl on
        // the sanitizer's allocator lock.
        int64_t f = -1;
        double t_s = 0;
        const bool ok = nlohmann::json::accept(line) && top_level_number(line, "frame", f) &&
                        top_level_number(line, "t", t_s);
        std::lock_guard lock(st->mu);
        ++st->lines;
        if (!ok) {
          ++st->bad;
          continue;
        }
        if (st->last_frame >= 0 && f > st->last_frame + 1)
          st->gaps += static_cast<uint64_t>(f - st->last_frame - 1);
        st->last_frame = f;
        if (st->latencies_ms.size() < 200000) st->latencies_ms.push_back((now_s - t_s) * 1e3);
      }
      buf.erase(0, start);
    }
  });
}

StreamClient::~StreamClient() {
  stop();
}

void StreamClient::stop() {
  st_->stop = true;
  if (st_->thread.joinable()) st_->thread.join();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

uint64_t StreamClient::lines() const {
  std::lock_guard lock(st_->mu);
  return st_->lines;
}
uint64_t StreamClient::bad_lines() const {
  std::lock_guard lock(st_->mu);
  return st_->bad;
}
uint64_t StreamClient::frame_gaps() const {
  std::lock_guard lock(st_->mu);
  return st_->gaps;
}
int64_t StreamClient::last_frame() const {
  std::lock_guard lock(st_->mu);
  return st_->last_frame;
}
std::vector<double> StreamClient::latencies_ms() const {
  std::lock_guard lock(st_->mu);
  return st_->latencies_ms;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1,
                            static_cast<size_t>(std::ceil(p / 100.0 * v.size())) - (p > 0 ? 1 : 0));
  return v[k];
}

}  // namespace mocap::reliability
