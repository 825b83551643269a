// SlimeVR decoder (see slimevr_decoder.hpp): boards by address, packet numbers, the replies a
// server owes, and one orientation sample per rotation of a mapped (MAC, sensor id).
#include "slimevr_decoder.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "decoders.hpp"

namespace mocap {

namespace sv = slimevr;

namespace {

constexpr int64_t kHeartbeatNs = 500'000'000;
constexpr int64_t kPingNs = 1'000'000'000;
constexpr int64_t kHoldNs = 100'000'000;  // a resting tracker's orientation repeated this often
// ... while its board was heard this recently (it echoes the 0.5 s heartbeats): a board that
// went silent is not kept alive by repeats, so it shows stale, then disconnected at timeout_ns.
constexpr int64_t kAliveNs = 1'000'000'000;
constexpr double kGravity_m_s2 = 9.80665;

int parse_int(std::string_view s, int lo, int hi) {
  int v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || v < lo || v > hi) return -1;
  return v;
}

}  // namespace

std::vector<SlimeMapping> slime_mappings(const DeviceSpec& spec) {
  std::vector<SlimeMapping> out;
  const auto bad = [&](const std::string& what) {
    return std::invalid_argument("device " + spec.name + ": " + what);
  };
  const std::string trackers = option_string(spec, "trackers", "");
  if (!trackers.empty()) {
    std::string_view rest = trackers;
    while (!rest.empty()) {
      const auto semi = rest.find(';');
      std::string_view item = rest.substr(0, semi);
      rest = semi == std::string_view::npos ? std::string_view{} : rest.substr(semi + 1);
      SlimeMapping m;
      if (const auto at = item.find('@'); at != std::string_view::npos) {
        m.axis_remap = std::string(item.substr(at + 1));
        item = item.substr(0, at);
      }
      const auto slash = item.find('/'), eq = item.find('=');
      int id = -1, idx = -1;
      if (slash != std::string_view::npos && eq != std::string_view::npos && slash < eq) {
        id = parse_int(item.substr(slash + 1, eq - slash - 1), 0, 255);
        idx = parse_int(item.substr(eq + 1), 0, 65535);
      }
      if (id < 0 || idx < 0 || !sv::parse_mac(item.substr(0, slash), m.mac))
        throw bad("trackers: \"" + std::string(item) +
                  "\" is not MAC/SENSOR=INDEX[@AXIS_REMAP] (e.g. AA:BB:CC:DD:EE:FF/0=3)");
      m.tracker_sensor = static_cast<uint8_t>(id);
      m.sensor_id = static_cast<uint16_t>(idx);
      out.push_back(m);
    }
    return out;
  }
  SlimeMapping m;
  const std::string mac = option_string(spec, "mac", "");
  if (mac.empty())
    throw bad("a slimevr sensor needs options.mac, the tracker's MAC (mocap devices lists them)");
  if (!sv::parse_mac(mac, m.mac))
    throw bad("options.mac \"" + mac + "\" is not a MAC like AA:BB:CC:DD:EE:FF");
  const double id = option_double(spec, "tracker", 0);
  if (!(id >= 0 && id <= 255) || id != static_cast<int>(id))
    throw bad("options.tracker must be the sensor number on the board, 0..255");
  m.tracker_sensor = static_cast<uint8_t>(id);
  m.sensor_id = spec.first_sensor_id;
  out.push_back(m);
  return out;
}

SlimeVrDecoder::SlimeVrDecoder(const DeviceSpec& spec) {
  if (!spec.port.empty() && spec.port.rfind("udp:", 0) != 0)
    throw std::invalid_argument("device " + spec.name +
                                ": a slimevr port is udp:HOST:PORT (trackers talk to "
                                "udp:0.0.0.0:6969), not \"" +
                                spec.port + "\"");
  for (const SlimeMapping& m : slime_mappings(spec)) {
    DeviceSpec one = spec;
    one.first_sensor_id = m.sensor_id;
    if (!m.axis_remap.empty()) one.axis_remap = m.axis_remap;
    sensors_.push_back(Sensor{m, DecoderCommon(one), -1});
  }
}

uint64_t SlimeVrDecoder::replies(uint32_t type) const {
  return type < reply_count_.size() ? reply_count_[type] : 0;
}

std::vector<SlimeBoardInfo> SlimeVrDecoder::boards() const {
  std::vector<SlimeBoardInfo> out;
  for (const Board& b : boards_)
    if (b.used && b.hello)
      out.push_back({b.ip, b.port, b.mac, b.board, b.imu, b.mcu, b.protocol_version,
                     std::string(b.firmware.data(), b.firmware_len)});
  return out;
}

std::size_t SlimeVrDecoder::board_count() const {
  std::size_t n = 0;
  for (const Board& b : boards_)
    n += b.used && b.hello;
  return n;
}

int SlimeVrDecoder::board_for(uint32_t ip, uint16_t port, int64_t t_ns) {
  int free = -1, oldest = 0;
  for (std::size_t i = 0; i < boards_.size(); ++i) {
    const Board& b = boards_[i];
    if (b.used && b.ip == ip && b.port == port) return static_cast<int>(i);
    if (!b.used && free < 0) free = static_cast<int>(i);
    if (b.last_heard_ns < boards_[static_cast<std::size_t>(oldest)].last_heard_ns)
      oldest = static_cast<int>(i);
  }
  const int i = free >= 0 ? free : oldest;  // full: the longest-silent board makes room
  Board& b = boards_[static_cast<std::size_t>(i)];
  b = Board{};
  b.used = true;
  b.ip = ip;
  b.port = port;
  b.last_heard_ns = t_ns;
  for (Sensor& s : sensors_)
    if (s.board == i) s.board = -1;
  return i;
}

void SlimeVrDecoder::queue(const Board& b, std::span<const uint8_t> bytes) {
  if (n_replies_ == replies_.size() || bytes.size() > 64) return;  // the device drains each read
  Reply& r = replies_[n_replies_++];
  r.ip = b.ip;
  r.port = b.port;
  r.len = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), r.bytes.begin());
}

void SlimeVrDecoder::feed(std::span<const uint8_t> record, int64_t t_host_ns, SampleSink& sink) {
  stats_.bytes += record.size();
  if (record.size() < kSlimeRecordHeader) {
    ++stats_.resyncs;
    return;
  }
  const uint32_t ip =
      uint32_t{record[0]} << 24 | uint32_t{record[1]} << 16 | uint32_t{record[2]} << 8 | record[3];
  const uint16_t port = static_cast<uint16_t>(record[4] << 8 | record[5]);
  const auto datagram = record.subspan(kSlimeRecordHeader);
  sv::Error err = sv::Error::kNone;
  const std::size_t n = sv::parse_datagram(datagram, packets_, err);
  if (err != sv::Error::kNone) ++stats_.resyncs;  // malformed or unknown part, counted
  if (n == 0) return;
  const int bi = board_for(ip, port, t_host_ns);
  Board& b = boards_[static_cast<std::size_t>(bi)];
  // Packet numbers: 0 restarts the count (handshakes, echoes); older numbers are stale.
  uint64_t number = 0;
  if (datagram.size() >= 12)
    for (int i = 4; i < 12; ++i)
      number = number << 8 | datagram[static_cast<std::size_t>(i)];
  if (number != 0 && number <= b.last_number) {
    ++stats_.dropped_samples;  // out of order: dropped like the server does
    return;
  }
  b.last_number = number;
  b.last_heard_ns = t_host_ns;
  ++stats_.frames;
  for (std::size_t i = 0; i < n; ++i)
    handle(bi, packets_[i], t_host_ns, sink);
  if (packets_[0].type == sv::kHandshake && b.hello) {
    b.hello_len = std::min(record.size(), b.hello_record.size());
    std::copy_n(record.begin(), b.hello_len, b.hello_record.begin());
  }
  for (Sensor& s : sensors_) {
    if (s.board == bi && s.new_quat) emit(s, t_host_ns, sink, 0, number);
    if (s.telemetry_changed) {
      s.telemetry_changed = false;
      sink.on_telemetry(s.map.sensor_id, s.telemetry);
    }
  }
}

template <class F>
void SlimeVrDecoder::update_telemetry(int bi, int only, F&& f) {
  for (Sensor& s : sensors_) {
    if (s.board != bi || (only >= 0 && only < 255 && s.map.tracker_sensor != only)) continue;
    const SensorTelemetry before = s.telemetry;
    f(s.telemetry);
    s.telemetry_changed = s.telemetry_changed || !(before == s.telemetry);
  }
}

void SlimeVrDecoder::handle(int bi, const sv::Packet& p, int64_t t_ns, SampleSink& sink) {
  Board& b = boards_[static_cast<std::size_t>(bi)];
  if (p.type < reply_count_.size()) ++reply_count_[p.type];
  switch (p.type) {
    case sv::kHandshake: {
      std::array<uint8_t, sv::kHandshakeReplySize> reply{};
      sv::write_handshake_reply(reply);
      queue(b, reply);
      b.hello = true;
      b.mac = p.mac;
      b.board = p.board;
      b.imu = p.handshake_imu;
      b.mcu = p.mcu;
      b.protocol_version = p.protocol_version;
      b.firmware = p.firmware;
      b.firmware_len = p.firmware_len;
      for (Sensor& s : sensors_) {
        if (s.map.mac != b.mac) continue;
        if (s.board >= 0 && s.board != bi) boards_[static_cast<std::size_t>(s.board)].used = false;
        s.board = bi;
      }
      update_telemetry(bi, -1, [&](SensorTelemetry& t) {
        set_named(t.board, sv::board_name(p.board), "board", p.board);
        if (t.imu[0] == 0) set_named(t.imu, sv::imu_name(p.handshake_imu), "IMU", p.handshake_imu);
        set_named(t.mcu, sv::mcu_name(p.mcu), "MCU", p.mcu);
        SensorTelemetry::set(t.firmware, p.firmware_text());
        SensorTelemetry::set(t.address, sv::mac_string(p.mac));
      });
      return;
    }
    case sv::kSensorInfo: {
      std::array<uint8_t, 6> ack{};
      sv::write_sensor_info_ack(ack, p.sensor_id, p.sensor_state);
      queue(b, ack);
      if (p.imu_type != 0)  // this sensor's own IMU (the handshake names the board's first)
        update_telemetry(bi, p.sensor_id, [&](SensorTelemetry& t) {
          set_named(t.imu, sv::imu_name(p.imu_type), "IMU", p.imu_type);
        });
      return;
    }
    case sv::kSignalStrength:
      update_telemetry(bi, p.sensor_id,
                       [&](SensorTelemetry& t) { t.rssi_dbm = static_cast<float>(p.rssi_dbm); });
      return;
    case sv::kTemperature:
      if (std::isfinite(p.temperature_c))
        update_telemetry(bi, p.sensor_id,
                         [&](SensorTelemetry& t) { t.temperature_c = p.temperature_c; });
      return;
    case sv::kFeatureFlags: {
      std::array<uint8_t, 13> flags{};
      sv::write_feature_flags(flags, 0, 0x01);  // bit 0: we take bundles (100, 101)
      queue(b, flags);
      return;
    }
    case sv::kBattery:
      update_telemetry(bi, -1, [&](SensorTelemetry& t) {
        if (std::isfinite(p.battery_level) && p.battery_level >= 0)
          t.battery_fraction = std::min(p.battery_level, 1.0f);
        if (std::isfinite(p.battery_v) && p.battery_v > 0) t.battery_v = p.battery_v;
      });
      return;
    case sv::kUserAction: {
      if (p.action != sv::kResetFull && p.action != sv::kResetYaw && p.action != sv::kResetMounting)
        return;  // pause tracking: not ours to act on
      const ResetRequest r = p.action == sv::kResetYaw ? ResetRequest::heading : ResetRequest::full;
      for (const Sensor& s : sensors_)
        if (s.board == bi) {
          sink.on_reset_request(s.map.sensor_id, r);
          break;
        }
      return;
    }
    default:
      break;
  }
  if (!p.has_quat && !p.has_accel) return;
  if (p.type == sv::kRotationData && p.data_type != 1) return;  // corrections: not a rotation
  for (Sensor& s : sensors_) {
    if (s.board != bi || s.map.tracker_sensor != p.sensor_id) continue;
    if (p.has_quat) {
      // x, y, z, w on the wire; zero or non-finite: dropped by DecoderCommon.
      s.q = Eigen::Quaterniond(p.quat_xyzw[3], p.quat_xyzw[0], p.quat_xyzw[1], p.quat_xyzw[2]);
      s.new_quat = true;
    }
    if (p.has_accel) {
      s.lin_acc_m_s2 = Eigen::Vector3d(p.accel[0], p.accel[1], p.accel[2]);
      s.has_acc = true;
    }
  }
  (void)t_ns;
}

void SlimeVrDecoder::emit(Sensor& s, int64_t t_ns, SampleSink& sink, uint8_t flags,
                          uint64_t number) {
  s.new_quat = false;
  const double norm = s.q.norm();
  if (!std::isfinite(norm) || norm < 0.5 || norm > 1.5) {
    ++stats_.implausible;  // a zero (not yet started) or damaged quaternion: no orientation
    return;
  }
  ImuSample out;
  out.q_device_sensor = s.q;
  out.valid = kFieldQuat;
  // A board counts its packets from its start: a rotation numbered below the last one seen
  // (accepted after a handshake, which restarts the count) is from a board that rebooted. One
  // back after a silence with its count going on (from the same address or another) did not:
  // its fusion ran on.
  const bool restarted = number != 0 && static_cast<uint32_t>(number) < s.number;
  out.flags = flags | (restarted ? kFlagDeviceRestarted : 0);
  s.last_emit_ns = t_ns;
  if (s.has_acc) {
    // The tracker sends linear acceleration (gravity removed) in the sensor frame; the sample
    // carries specific force, so gravity is put back through the tracker's own orientation.
    const Eigen::Quaterniond q = s.q.normalized();
    out.acc_m_s2 = s.lin_acc_m_s2 + q.conjugate() * Eigen::Vector3d(0, 0, kGravity_m_s2);
    out.valid |= kFieldAcc;
  }
  if (!s.connected) {
    s.connected = true;
    sink.on_connection(s.map.sensor_id, true,
                       "tracker " + sv::mac_string(s.map.mac) + " sensor " +
                           std::to_string(s.map.tracker_sensor) + " streaming");
  }
  // The sample's number is the board's packet number (a hold repeats its rotation's).
  if (number != 0) s.number = static_cast<uint32_t>(number);
  if (s.number != 0) s.common.set_next_seq(s.number);
  const uint64_t before = s.common.stats.samples;
  s.common.emit_untimed(out, t_ns, sink);
  stats_.samples += s.common.stats.samples - before;
}

void SlimeVrDecoder::tick(int64_t t_ns, SampleSink& sink) {
  for (std::size_t i = 0; i < boards_.size(); ++i) {
    Board& b = boards_[i];
    if (!b.used) continue;
    if (t_ns - b.last_heard_ns > timeout_ns) {
      b.used = false;  // its next handshake is answered afresh
      for (Sensor& s : sensors_) {
        if (s.board != static_cast<int>(i)) continue;
        s.board = -1;
        if (s.connected)
          sink.on_connection(s.map.sensor_id, false,
                             "tracker " + sv::mac_string(s.map.mac) + " silent for " +
                                 std::to_string(timeout_ns / 1'000'000) + " ms");
        s.connected = false;
      }
      continue;
    }
    if (!b.hello) continue;
    for (Sensor& s : sensors_)
      if (s.board == static_cast<int>(i) && s.connected && t_ns - s.last_emit_ns >= kHoldNs &&
          t_ns - b.last_heard_ns <= kAliveNs)
        emit(s, t_ns, sink, kFlagInterpolated);  // at rest: the same orientation, still alive
    if (t_ns - b.last_heartbeat_ns >= kHeartbeatNs) {
      b.last_heartbeat_ns = t_ns;
      std::array<uint8_t, 12> hb{};
      sv::write_heartbeat(hb, ++b.heartbeat_number);
      queue(b, hb);
    }
    if (t_ns - b.last_ping_ns >= kPingNs) {
      b.last_ping_ns = t_ns;
      std::array<uint8_t, 16> ping{};
      sv::write_ping(ping, 0, next_ping_id_++);
      queue(b, ping);
    }
  }
}

std::unique_ptr<ProtocolDecoder> make_slimevr_decoder(const DeviceSpec& spec) {
  return std::make_unique<SlimeVrDecoder>(spec);
}

}  // namespace mocap
