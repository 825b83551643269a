// Shared by the live benchmarks (latency, capacity): simulated WitMotion sensors on real ptys
// (or SlimeVR tracker boards on real UDP sockets), a spawned mocapd (real drivers, pipeline,
// JSON server) configured to read them, and /proc readings of the daemon's CPU time and memory.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mocap/devsim/sim_encoder.hpp"

namespace mocap::bench {

struct RigOptions {
  int sensors = 17;
  double rate_hz = 200;
  bool publish_every_sample = false;
  double frame_rate_hz = 120;
  int realtime_priority = 0;  ///< mocapd's pipeline.realtime_priority
  /// "witmotion" (a pty each), "slimevr" (a UDP board each, one sensor per board, talking to
  /// mocapd's SlimeVR port: handshake, then one rotation datagram per sample) or "line-udp"
  /// (the DIY line protocol, one datagram per sample to a UDP port of its own per sensor).
  std::string protocol = "witmotion";
  /// mocapd's pipeline.read_batch_ms; < 0: its default.
  double read_batch_ms = -1;
};

/// N ptys with a WitMotion encoder each (or N SlimeVR boards), and a mocapd reading them.
class DaemonRig {
 public:
  explicit DaemonRig(const RigOptions& o);  ///< spawns mocapd; throws std::runtime_error
  ~DaemonRig();                             ///< stops mocapd (SIGTERM, then waits)
  /// Encodes one sample of sensor i (device time t_device_ns) and writes it to its pty (or
  /// sends its board's rotation datagram). key (if given) receives what the daemon's frames
  /// will show of this sample (SensorStatus): WitMotion its device time as the device sends it
  /// (whole ms, in ns: frames' t_device_ns), SlimeVR its packet number (frames' seq).
  bool write_sample(int i, int64_t t_device_ns, uint64_t* key = nullptr);
  /// The simulated devices' clock at monotonic time t_mono_ns: it started with the rig and
  /// runs in step with the host (a device keeps sampling while the bench pauses), ns.
  int64_t device_ns(int64_t t_mono_ns) const { return t_mono_ns - start_ns_; }
  /// Answers host commands on every pty (the driver configures its device at open); SlimeVR:
  /// reads the server's datagrams and repeats the handshake of boards not yet answered.
  /// Returns how many host bytes the ptys carried (0 for SlimeVR).
  size_t answer_host();
  int json_port() const { return port_; }
  pid_t pid() const { return pid_; }
  /// `status` over the control socket (one JSON line), "" on failure.
  std::string status() const;
  /// Waits until every sensor is streaming (status) and its device is set up (WitMotion: no
  /// host command for 300 ms, so the output content the driver asked for is in force; SlimeVR:
  /// every board's handshake answered), up to timeout_s.
  bool wait_streaming(double timeout_s);
  /// Keeps every sensor writing (a sample each 10 ms, stamped with the device clock) and the
  /// host answered for `seconds`: the devices never fall silent between warm-up and a run.
  /// Returns the monotonic time of the last writes.
  int64_t keep_alive(double seconds);
  /// Stops mocapd (SIGTERM) and returns its exit status; idempotent.
  int stop();
  const std::string& log_path() const { return log_; }
  /// The last lines of mocapd's log (its directory goes with the rig).
  std::string log_tail() const;

 private:
  RigOptions opt_;
  std::vector<std::unique_ptr<PtyEndpoint>> ptys_;
  std::vector<int> line_fds_;  ///< line-udp: each sensor's socket, connected to its port
  std::vector<std::unique_ptr<ProtocolEncoder>> enc_;
  struct SlimeBoard {
    int fd = -1;
    uint64_t number = 0;
    bool answered = false;
  };
  std::vector<SlimeBoard> boards_;
  std::vector<uint8_t> bytes_, reply_;
  std::string dir_, ctl_, log_;
  std::vector<int> udp_ports_;  ///< ports picked for the daemon (kept distinct)
  int port_ = 0;
  int64_t start_ns_ = 0;  ///< monotonic time of the devices' clock origin
  pid_t pid_ = -1;
  int exit_status_ = -1;
};

/// CPU seconds (user + system) of a process, from /proc/PID/stat.
double process_cpu_s(pid_t pid);
/// VmRSS and VmHWM of a process in MB (from /proc/PID/status); -1 if unreadable.
double process_rss_mb(pid_t pid);
double process_hwm_mb(pid_t pid);
/// CPU seconds of the calling thread.
double thread_cpu_s();
/// The 1-minute load average.
double load_average_1m();
/// Opens a TCP connection to 127.0.0.1:port, retrying up to timeout_s; -1 on failure.
int connect_loopback(int port, double timeout_s);

}  // namespace mocap::bench
