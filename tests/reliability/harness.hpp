// Harness for the reliability suite: runs the real mocapd binary as a child process with a
// generated rig configuration, talks to it over its control socket and JSON stream, and drives
// line-protocol sensors through real pseudo-terminals (so a test can inject any byte-level fault).
#pragma once

#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../common/run_program.hpp"
#include "mocap/devsim/sim_encoder.hpp"

namespace mocap::reliability {

using test::Result;
using test::run;
using test::slurp_file;

/// A fresh directory under /tmp, removed (recursively) on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

/// A TCP / UDP port that was free a moment ago on 127.0.0.1.
int free_tcp_port();
int free_udp_port();

/// Polls pred every 20 ms until it is true or timeout passes; returns the last result.
bool wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout);

/// One DIY line-protocol sensor on a pseudo-terminal reached through a stable symlink. The test
/// writes lines (or any bytes) itself; vanish()/reappear() close the pty and make a new one at
/// the same link, like a USB serial adapter unplugged and plugged back in.
class LineSensorPty {
 public:
  explicit LineSensorPty(std::string link_path);
  const std::string& link() const { return link_; }
  /// One sample line at device time t_us (the line's time field, wrapped by the caller).
  bool write_sample(uint64_t t_us, double phase);
  /// Any bytes (garbage, truncated frames).
  bool write_bytes(const std::string& bytes);
  void vanish();
  void reappear();

 private:
  std::string link_;
  std::mutex mu_;  // guards pty_
  std::unique_ptr<PtyEndpoint> pty_;
};

/// Byte-level faults a LineFeeder can inject into one sensor's stream.
/// glitch: every 10th sample a valid line reading 5000 deg/s (beyond any 2000 deg/s gyro).
enum class FaultMode { normal, garbage, truncated, wrong_baud, flood, silent, glitch };

/// Writes every sensor's samples at 100 Hz (device time in microseconds) on its own thread,
/// with a per-sensor fault mode the test changes while it runs.
class LineFeeder {
 public:
  struct Sensor {
    LineSensorPty* pty;
    uint64_t wrap_mask;  ///< the time field wraps at this mask + 1
    uint64_t t_us;       ///< device time of the next sample (before wrapping)
    std::atomic<FaultMode> mode{FaultMode::normal};
    std::atomic<uint64_t> written{0};
    uint64_t ticks = 0;  ///< feeder thread only
  };
  explicit LineFeeder(std::vector<Sensor*> sensors);
  ~LineFeeder();
  /// Jumps one sensor's device clock (at the next tick) by dt_us (may be negative).
  void jump(size_t i, int64_t dt_us);

 private:
  void run();
  std::vector<Sensor*> sensors_;
  std::mutex mu_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Two healthy line sensors "a" (pelvis) and "b" (torso) on ptys, fed at 100 Hz.
struct TwoSensorRig {
  explicit TwoSensorRig(const TempDir& dir);
  std::string sensors_toml() const;  ///< their [[sensor]] tables
  LineSensorPty a, b;
  LineFeeder::Sensor fa, fb;
  LineFeeder feeder;
};

/// The real mocapd, started with a configuration written to dir/<name>.toml. Its stderr goes to
/// dir/<name>.log. Killed (SIGKILL) on destruction if still running.
class Daemon {
 public:
  Daemon(const TempDir& dir, std::string name, const std::string& config_toml,
         std::vector<std::string> extra_args = {});
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  pid_t pid() const { return pid_; }
  const std::string& socket() const { return socket_; }
  const std::string& log_path() const { return log_; }
  std::string log_text() const;

  /// Sends one control request line; returns the parsed JSON reply (throws if unreachable).
  nlohmann::json call(const std::string& line, int timeout_ms = 5000) const;
  nlohmann::json status() const { return call("status"); }
  /// True once the control socket answers `status` (false if the process died first).
  bool wait_ready(std::chrono::milliseconds timeout);
  bool running();
  /// SIGKILL and reap; returns the wait status.
  int kill9();
  /// `quit` over the socket (or SIGTERM if that fails) and reap; returns the exit code.
  int quit(std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// Resident memory (kB) and open file descriptors of the process, from /proc.
  long rss_kb() const;
  int fd_count() const;

 private:
  std::string socket_, log_;
  pid_t pid_ = -1;
  bool reaped_ = false;
};

/// Configuration text shared by the tests: control socket, JSON stream port, no shared-memory
/// posture (tests run in parallel), no VMC, plus `extra` appended verbatim.
std::string base_config(const TempDir& dir, int json_port, const std::string& extra = "");
/// A [[sensor]] table for a line-protocol sensor on `port`.
std::string line_sensor_toml(const std::string& name, const std::string& port,
                             const std::string& segment, const std::string& units = "");

/// A sensor entry of a status reply by name ({} if absent, e.g. before the first frame).
nlohmann::json sensor_status(const nlohmann::json& status, const std::string& name);

/// A JSON-stream client on its own thread: counts lines, checks each parses, remembers the last
/// frame number and how many frame numbers were skipped, and the latency (receive time minus
/// the frame's host time "t") of every line.
class StreamClient {
 public:
  explicit StreamClient(int port, bool read = true);
  ~StreamClient();
  bool connected() const { return fd_ >= 0; }
  uint64_t lines() const;
  uint64_t bad_lines() const;
  uint64_t frame_gaps() const;  ///< frames missing between consecutive lines
  int64_t last_frame() const;
  std::vector<double> latencies_ms() const;
  void stop();

 private:
  struct State;
  int fd_ = -1;
  std::shared_ptr<State> st_;
};

/// True once sensors "a" and "b" (a TwoSensorRig's) both report "streaming" in d's status.
bool both_streaming(Daemon& d);

/// The suite's usual set-up: a fresh directory, a TwoSensorRig in it and mocapd on it
/// (base_config with a fresh JSON stream port and `extra_config`, then the sensors' tables;
/// `extra_args` on its command line). The test checks d.wait_ready() or ready_and_streaming()
/// before using it.
struct TwoSensorDaemon {
  explicit TwoSensorDaemon(const std::string& name, std::vector<std::string> extra_args = {},
                           const std::string& extra_config = "");
  /// True once mocapd answers and both sensors are streaming (15 s each at most).
  bool ready_and_streaming();
  TempDir dir;
  TwoSensorRig rig;
  int json_port;
  Daemon d;
};

/// Runs <build>/bin/<program> with `args` to completion (killed by timeout(1) after timeout_s
/// if that is > 0); its exit code, stdout and stderr.
Result run_bin(const std::string& program, const std::vector<std::string>& args, int timeout_s = 0);

/// Tries to connect to the Unix socket at `path` as another user (nobody, from a forked child,
/// so the caller must be root): 0 = refused by the kernel (EACCES), 1 = connected, 2 = another
/// errno, 3 = could not become nobody, -1 = the child did not exit normally.
int connect_unix_as_nobody(const std::string& path);

/// Nearest-rank percentile of a sample (sorted copy); 0 for an empty sample.
double percentile(std::vector<double> v, double p);

}  // namespace mocap::reliability
