// The simulated SlimeVR tracker (see sim_slimevr.hpp): firmware packet writers and the board's
// connection state machine over a real UDP socket.
#include "mocap/devsim/sim_slimevr.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "mocap/core/time.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/drivers/transport.hpp"

namespace mocap {

namespace slime_sim {
namespace {
void u8(std::vector<uint8_t>& o, uint8_t v) {
  o.push_back(v);
}
void u32(std::vector<uint8_t>& o, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8)
    o.push_back(static_cast<uint8_t>(v >> s));
}
void u64(std::vector<uint8_t>& o, uint64_t v) {
  u32(o, static_cast<uint32_t>(v >> 32));
  u32(o, static_cast<uint32_t>(v));
}
void f32(std::vector<uint8_t>& o, double v) {
  u32(o, std::bit_cast<uint32_t>(static_cast<float>(v)));
}
void header(std::vector<uint8_t>& o, uint32_t type, uint64_t number) {
  u32(o, type);
  u64(o, number);
}
}  // namespace

void handshake(const slimevr::Mac& mac, std::vector<uint8_t>& out) {
  header(out, slimevr::kHandshake, 0);
  u32(out, 9);   // board: BOARD_SLIMEVR
  u32(out, 11);  // IMU: BMI270
  u32(out, 1);   // MCU: ESP8266
  u32(out, 0), u32(out, 0), u32(out, 0);
  u32(out, 22);  // protocol (firmware build) version
  const char fw[] = "0.6.0-sim";
  u8(out, sizeof fw - 1);
  out.insert(out.end(), fw, fw + sizeof fw - 1);
  out.insert(out.end(), mac.begin(), mac.end());
  u8(out, 0);  // tracker type
  for (int i = 0; i < 5; ++i)
    u8(out, 0);  // five empty strings (vendor, product, ...)
}

void sensor_info(uint64_t number, uint8_t sensor, std::vector<uint8_t>& out) {
  header(out, slimevr::kSensorInfo, number);
  u8(out, sensor);
  u8(out, 1);   // state: OK
  u8(out, 11);  // IMU type: BMI270
  for (int i = 0; i < 13; ++i)
    u8(out, 0);  // sensor config, calibration flags, position, data type, reserved (28 bytes)
}

void rotation(uint64_t number, uint8_t sensor, const Eigen::Quaterniond& q,
              std::vector<uint8_t>& out) {
  header(out, slimevr::kRotationData, number);
  u8(out, sensor);
  u8(out, 1);  // data type: normal rotation
  f32(out, q.x()), f32(out, q.y()), f32(out, q.z()), f32(out, q.w());
  u8(out, 0);  // accuracy
}

void acceleration(uint64_t number, uint8_t sensor, const Eigen::Vector3d& a,
                  std::vector<uint8_t>& out) {
  header(out, slimevr::kAccel, number);
  f32(out, a.x()), f32(out, a.y()), f32(out, a.z());
  u8(out, sensor);
}

void heartbeat(uint64_t number, std::vector<uint8_t>& out) {
  header(out, slimevr::kHeartbeat, number);
}

void user_action(uint64_t number, uint8_t action, std::vector<uint8_t>& out) {
  header(out, slimevr::kUserAction, number);
  u8(out, action);
}

void battery(uint64_t number, double voltage_v, double level, std::vector<uint8_t>& out) {
  header(out, slimevr::kBattery, number);
  f32(out, voltage_v);
  f32(out, level);
}

void signal_strength(uint64_t number, int8_t rssi_dbm, std::vector<uint8_t>& out) {
  header(out, slimevr::kSignalStrength, number);
  u8(out, 255);  // the board's, not one sensor's
  u8(out, static_cast<uint8_t>(rssi_dbm));
}

void temperature(uint64_t number, uint8_t sensor, double celsius, std::vector<uint8_t>& out) {
  header(out, slimevr::kTemperature, number);
  u8(out, sensor);
  f32(out, celsius);
}

}  // namespace slime_sim

SimSlimeTracker::SimSlimeTracker(SimSlimeOptions opt) : opt_(std::move(opt)) {
  if (!slimevr::parse_mac(opt_.mac, mac_))
    throw std::invalid_argument("mac \"" + opt_.mac + "\": expected AA:BB:CC:DD:EE:FF");
  if (opt_.sensors < 1 || opt_.sensors > 10)
    throw std::invalid_argument("sensors: 1..10 IMUs on a board");
  if (!(opt_.rate_hz > 0 && opt_.rate_hz <= 1000))
    throw std::invalid_argument("rate: 0 < Hz <= 1000");
  if (!std::isnan(opt_.battery_v) && !(opt_.battery_v > 0 && opt_.battery_v < 10))
    throw std::invalid_argument("battery_v: volts, 0 < V < 10");
  if (!std::isnan(opt_.battery_pct) && !(opt_.battery_pct >= 0 && opt_.battery_pct <= 100))
    throw std::invalid_argument("battery_pct: 0..100");
  if (!std::isnan(opt_.rssi_dbm) && !(opt_.rssi_dbm >= -128 && opt_.rssi_dbm <= 0))
    throw std::invalid_argument("rssi: dBm, -128..0");
  if (!std::isnan(opt_.temperature_c) && !(opt_.temperature_c > -60 && opt_.temperature_c < 150))
    throw std::invalid_argument("temperature: degrees C, -60..150");
  if (!opt_.sensor_motions.empty() &&
      opt_.sensor_motions.size() != static_cast<std::size_t>(opt_.sensors))
    throw std::invalid_argument("sensor_motions: one motion per IMU");
  motion_ = make_motion(opt_.motion);
  info_acked_.assign(static_cast<std::size_t>(opt_.sensors), false);
  last_sent_.assign(static_cast<std::size_t>(opt_.sensors), std::nullopt);
  std::string host, port, err;
  if (!split_host_port(opt_.server, host, port, err)) throw std::invalid_argument(err);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &res);
  if (rc != 0) throw std::runtime_error("udp " + opt_.server + ": " + gai_strerror(rc));
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  const bool ok = fd_ >= 0 && ::connect(fd_, res->ai_addr, res->ai_addrlen) == 0;
  freeaddrinfo(res);
  if (!ok) throw std::runtime_error("udp " + opt_.server + ": " + std::strerror(errno));
}

SimSlimeTracker::~SimSlimeTracker() {
  stop();
  if (fd_ >= 0) ::close(fd_);
}

void SimSlimeTracker::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { run(); });
}

void SimSlimeTracker::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void SimSlimeTracker::press(slimevr::UserAction action) {
  pending_action_ = action;
}

void SimSlimeTracker::send(const std::vector<uint8_t>& bytes) {
  ::send(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT);
}

void SimSlimeTracker::receive(int64_t now_ns) {
  std::array<uint8_t, 512> in{};
  std::vector<uint8_t> out;
  for (;;) {
    const ssize_t n = ::recv(fd_, in.data(), in.size(), MSG_DONTWAIT);
    if (n <= 0) return;
    last_server_ns_ = now_ns;
    // The firmware's receive switch: handshake reply, heartbeat, ping, sensor-info ack.
    if (n >= 13 && in[0] == slimevr::kHandshake && std::memcmp(&in[1], "Hey OVR =D", 10) == 0) {
      if (!connected_) number_ = 0;
      connected_ = true;
      continue;
    }
    if (n < 4) continue;
    const uint32_t type = uint32_t{in[0]} << 24 | uint32_t{in[1]} << 16 | in[2] << 8 | in[3];
    if (type == slimevr::kServerHeartbeat) {
      out.clear();
      slime_sim::heartbeat(++number_, out);
      send(out);
    } else if (type == slimevr::kPingPong && n >= 16) {
      send(std::vector<uint8_t>(in.begin(), in.begin() + 16));  // echoed byte for byte
    } else if (type == slimevr::kSensorInfo && n >= 6 && in[4] < info_acked_.size()) {
      info_acked_[in[4]] = true;
    }
  }
}

void SimSlimeTracker::run() {
  constexpr int64_t kHandshakeEveryNs = 1'000'000'000, kServerTimeoutNs = 3'000'000'000;
  constexpr double kGravity_m_s2 = 9.80665;
  std::vector<uint8_t> out;
  out.reserve(512);
  const int64_t period_ns = static_cast<int64_t>(1e9 / opt_.rate_hz);
  int64_t t_device_ns = 0, last_handshake_ns = INT64_MIN / 2, last_info_ns = INT64_MIN / 2,
          last_report_ns = INT64_MIN / 2;
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  while (!stop_) {
    const int64_t now = monotonic_ns();
    receive(now);
    if (connected_ && now - last_server_ns_ > kServerTimeoutNs) {
      connected_ = false;  // the server went away: handshake again, re-announce the sensors
      info_acked_.assign(info_acked_.size(), false);
    }
    if (!connected_) {
      if (now - last_handshake_ns >= kHandshakeEveryNs) {
        last_handshake_ns = now;
        out.clear();
        slime_sim::handshake(mac_, out);
        send(out);
        ++handshakes_;
      }
    } else {
      if (now - last_info_ns >= kHandshakeEveryNs) {
        last_info_ns = now;
        for (std::size_t k = 0; k < info_acked_.size(); ++k) {
          if (info_acked_[k]) continue;
          out.clear();
          slime_sim::sensor_info(++number_, static_cast<uint8_t>(k), out);
          send(out);
        }
      }
      if (now - last_report_ns >= kHandshakeEveryNs) {  // battery, signal, temperature
        last_report_ns = now;
        if (!std::isnan(opt_.battery_v) || !std::isnan(opt_.battery_pct)) {
          out.clear();
          slime_sim::battery(++number_, std::isnan(opt_.battery_v) ? 0.0 : opt_.battery_v,
                             std::isnan(opt_.battery_pct) ? 0.0 : opt_.battery_pct / 100, out);
          send(out);
        }
        if (!std::isnan(opt_.rssi_dbm)) {
          out.clear();
          slime_sim::signal_strength(++number_, static_cast<int8_t>(std::lround(opt_.rssi_dbm)),
                                     out);
          send(out);
        }
        for (int k = 0; k < opt_.sensors && !std::isnan(opt_.temperature_c); ++k) {
          out.clear();
          slime_sim::temperature(++number_, static_cast<uint8_t>(k), opt_.temperature_c, out);
          send(out);
        }
      }
      const int action = pending_action_.exchange(-1);
      if (action >= 0) {
        out.clear();
        slime_sim::user_action(++number_, static_cast<uint8_t>(action), out);
        send(out);
      }
      for (int k = 0; k < opt_.sensors; ++k) {
        const auto sk = static_cast<std::size_t>(k);
        const ImuSample truth = sk < opt_.sensor_motions.size()
                                    ? opt_.sensor_motions[sk]->at(t_device_ns)
                                    : motion_->at(t_device_ns + sensor_phase_ns(k));
        const Eigen::Quaterniond q = truth.q_device_sensor.normalized();
        auto& last = last_sent_[static_cast<size_t>(k)];
        if (opt_.optimize_updates && last && q.angularDistance(*last) < 1e-4) continue;
        last = q;
        // What the firmware sends: rotation, then linear acceleration in the sensor frame.
        const Eigen::Vector3d lin =
            truth.acc_m_s2 - q.conjugate() * Eigen::Vector3d(0, 0, kGravity_m_s2);
        out.clear();
        slime_sim::rotation(++number_, static_cast<uint8_t>(k), q, out);
        send(out);
        out.clear();
        slime_sim::acceleration(++number_, static_cast<uint8_t>(k), lin, out);
        send(out);
      }
      ++samples_;
    }
    t_device_ns += period_ns;
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1'000'000'000)
      next.tv_nsec -= 1'000'000'000, ++next.tv_sec;
    // Until the next sample: the server's words (replies, heartbeats, pings).
    for (;;) {
      const int64_t left_ns = (next.tv_sec * 1'000'000'000 + next.tv_nsec) - monotonic_ns();
      if (left_ns <= 0 || stop_) break;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(std::min<int64_t>(left_ns / 1'000'000 + 1, 20))) > 0)
        receive(monotonic_ns());
    }
  }
}

}  // namespace mocap
