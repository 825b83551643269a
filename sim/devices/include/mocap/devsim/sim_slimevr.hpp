// A simulated SlimeVR tracker board (firmware protocol 22): the packets the ESP firmware sends,
// written from truth motion, over a real UDP socket with the firmware's connection logic
// (handshake repeated until the server answers "Hey OVR =D", sensor info until acknowledged,
// pings echoed, back to handshaking after 3 s without a word from the server).
// `mocap simulate --protocol slimevr`, the end-to-end tests and `mocap bench latency` run it.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/drivers/slimevr.hpp"

namespace mocap {

class Motion;

// The tracker's packets (big-endian, as the firmware writes them); each appends to out.
namespace slime_sim {
void handshake(const slimevr::Mac& mac, std::vector<uint8_t>& out);
void sensor_info(uint64_t number, uint8_t sensor, std::vector<uint8_t>& out);
/// Packet 17 from q_earth_sensor (x, y, z, w floats), data type 1.
void rotation(uint64_t number, uint8_t sensor, const Eigen::Quaterniond& q,
              std::vector<uint8_t>& out);
/// Packet 4: linear acceleration (gravity removed), m/s^2, sensor frame; sensor id last.
void acceleration(uint64_t number, uint8_t sensor, const Eigen::Vector3d& a,
                  std::vector<uint8_t>& out);
void heartbeat(uint64_t number, std::vector<uint8_t>& out);
void user_action(uint64_t number, uint8_t action, std::vector<uint8_t>& out);
/// Packet 12: battery voltage (V) and level (0..1).
void battery(uint64_t number, double voltage_v, double level, std::vector<uint8_t>& out);
/// Packet 19: WiFi RSSI (dBm) of the board (sensor id 255, as the firmware sends it).
void signal_strength(uint64_t number, int8_t rssi_dbm, std::vector<uint8_t>& out);
/// Packet 20: a sensor's temperature (degrees C).
void temperature(uint64_t number, uint8_t sensor, double celsius, std::vector<uint8_t>& out);
}  // namespace slime_sim

struct SimSlimeOptions {
  std::string server = "127.0.0.1:6969";  ///< where handshakes go (the firmware broadcasts)
  std::string mac = "02:5E:00:00:00:01";
  int sensors = 1;  ///< IMUs on the board (sensor ids 0..n-1; each its own phase of the motion)
  double rate_hz = 100;
  std::string motion = "rotate";  ///< as make_motion
  /// When not empty: IMU k's truth is sensor_motions[k] (no phase offset; one per IMU), instead
  /// of `motion` (a test's live performer, each IMU on its own body segment).
  std::vector<std::shared_ptr<const Motion>> sensor_motions;
  /// The firmware's OPTIMIZE_UPDATES: a rotation is sent only when it changed (a resting
  /// tracker goes quiet but for its answers to the server).
  bool optimize_updates = false;
  /// What the board reports about itself once a second while connected (packets 12, 19, 20);
  /// NaN: not sent.
  double battery_v = std::numeric_limits<double>::quiet_NaN();
  double battery_pct = std::numeric_limits<double>::quiet_NaN();  ///< 0..100
  double rssi_dbm = std::numeric_limits<double>::quiet_NaN();     ///< -128..0
  double temperature_c = std::numeric_limits<double>::quiet_NaN();
};

class SimSlimeTracker {
 public:
  explicit SimSlimeTracker(SimSlimeOptions opt);  ///< throws on a bad option or address
  ~SimSlimeTracker();
  SimSlimeTracker(const SimSlimeTracker&) = delete;
  SimSlimeTracker& operator=(const SimSlimeTracker&) = delete;
  void start();
  void stop();
  /// Sends a user action (packet 21) at the next sample time.
  void press(slimevr::UserAction action);
  bool connected() const { return connected_; }
  uint64_t samples() const { return samples_; }
  uint64_t handshakes() const { return handshakes_; }
  const Motion& motion() const { return *motion_; }
  /// Device time of the truth sample sent for sensor k at step i (for truth comparisons).
  int64_t sensor_phase_ns(int k) const { return int64_t{k} * 250'000'000; }

 private:
  void run();
  void send(const std::vector<uint8_t>& bytes);
  void receive(int64_t now_ns);

  SimSlimeOptions opt_;
  slimevr::Mac mac_{};
  std::shared_ptr<const Motion> motion_;
  int fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false}, connected_{false};
  std::atomic<uint64_t> samples_{0}, handshakes_{0};
  std::atomic<int> pending_action_{-1};
  uint64_t number_ = 0;
  int64_t last_server_ns_ = 0;
  std::vector<bool> info_acked_;
  std::vector<std::optional<Eigen::Quaterniond>> last_sent_;  ///< per sensor, for optimize
};

}  // namespace mocap
