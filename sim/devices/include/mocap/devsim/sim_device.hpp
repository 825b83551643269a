// A complete simulated device: a known motion (truth), a protocol encoder and an endpoint
// (pseudo-terminal or UDP), run on its own thread at the device's rate, answering host commands.
// `mocap simulate` and the end-to-end driver tests run this.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "mocap/devsim/sim_encoder.hpp"

namespace mocap {

/// Truth motion as a pure function of device time (so a test can recompute the truth of any
/// decoded sample). Values in the device frame: gyro, specific force, field, orientation.
class Motion {
 public:
  virtual ~Motion() = default;
  virtual ImuSample at(int64_t t_device_ns) const = 0;
};
/// "static" (level, at rest), "rotate" (90 deg/s about z, with a 30 deg tilt wobble), or a CSV
/// file "t_s,gx,gy,gz,ax,ay,az,mx,my,mz[,qw,qx,qy,qz]" (rad/s, m/s^2, uT; held between rows,
/// looped). Throws std::invalid_argument naming the problem.
std::unique_ptr<Motion> make_motion(const std::string& spec);

struct SimOptions {
  std::string protocol;
  double rate_hz = 100;
  std::string motion = "static";
  /// When set, the truth comes from this motion instead of `motion` (a test's live performer).
  std::shared_ptr<const Motion> motion_source;
  std::map<std::string, std::string> options;  ///< passed to the encoder
  std::string pty_link;                        ///< pty mode: stable symlink to create ("" = none)
  std::string udp;       ///< UDP mode: HOST:PORT to send to (empty = pty mode)
  double drift_ppm = 0;  ///< device clock runs this much slow (+) vs the host
  // Fault injection (deterministic): every Nth sample is dropped / preceded by garbage /
  // has one byte corrupted (0 = never).
  int drop_every = 0, garbage_every = 0, corrupt_every = 0;
};

class SimulatedDevice {
 public:
  explicit SimulatedDevice(SimOptions opt);  ///< creates the endpoint; throws on error
  ~SimulatedDevice();
  void start();
  void stop();
  /// pty mode: the path a driver opens.
  std::string path() const;
  /// Closes the endpoint (the device vanishes) / creates a fresh one at the same link.
  void vanish();
  void reappear();
  uint64_t samples() const { return samples_; }
  uint64_t dropped() const { return dropped_; }
  const Motion& motion() const { return *motion_; }

 private:
  void run();
  SimOptions opt_;
  std::shared_ptr<const Motion> motion_;
  std::unique_ptr<ProtocolEncoder> enc_;
  mutable std::mutex mu_;  // guards the endpoints
  std::unique_ptr<PtyEndpoint> pty_;
  std::unique_ptr<UdpSender> udp_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> samples_{0}, dropped_{0};
};

}  // namespace mocap
