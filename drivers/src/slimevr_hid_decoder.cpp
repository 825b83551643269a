// Decoder of the SlimeVR HID receiver (driver "slimevr_hid"): receiver ids bound to tracker
// addresses by the register packets, orientation samples (the trackers' own filter output, as
// over UDP) per mapped address, trackers reported appearing (first data) and leaving (3 s
// without data while the receiver keeps reporting).
#include <cmath>
#include <cstdio>

#include "decoders.hpp"
#include "mocap/drivers/slimevr_hid.hpp"
#include "slimevr_decoder.hpp"

namespace mocap {
namespace {

namespace sh = slimevr_hid;

constexpr int64_t kLeaveNs = 3'000'000'000;
constexpr double kGravity_m_s2 = 9.80665;

class SlimeVrHidDecoder final : public ProtocolDecoder {
 public:
  explicit SlimeVrHidDecoder(const DeviceSpec& spec) {
    for (const SlimeMapping& m : slime_mappings(spec)) {
      DeviceSpec one = spec;
      one.first_sensor_id = m.sensor_id;
      if (!m.axis_remap.empty()) one.axis_remap = m.axis_remap;
      sensors_.push_back(Sensor{m, DecoderCommon(one)});
    }
  }

  void feed(std::span<const uint8_t> report, int64_t t_ns, SampleSink& sink) override {
    stats_.bytes += report.size();
    const std::size_t n = sh::parse_report(report, packets_);
    if (n == 0) ++stats_.resyncs;
    for (std::size_t i = 0; i < n; ++i) {
      const sh::Packet& p = packets_[i];
      ++stats_.frames;
      if (p.type == sh::kRegister) {
        // The address is little-endian on the wire; written most significant byte first.
        slimevr::Mac mac;
        for (std::size_t j = 0; j < 6; ++j)
          mac[j] = p.address[5 - j];
        for (Sensor& s : sensors_)
          if (s.map.mac == mac) {
            s.id = p.id;
            if (s.telemetry.address[0] == 0)  // once (register packets come in every report)
              update(s, [&](SensorTelemetry& t) {
                SensorTelemetry::set(t.address, slimevr::mac_string(mac));
              });
          }
        continue;
      }
      for (Sensor& s : sensors_) {
        if (s.id != p.id) continue;
        update(s, [&](SensorTelemetry& t) { take_telemetry(p, t); });
        if (p.has_quat) emit(s, p, t_ns, sink);
      }
    }
    for (Sensor& s : sensors_)
      if (s.telemetry_changed) {
        s.telemetry_changed = false;
        sink.on_telemetry(s.map.sensor_id, s.telemetry);
      }
    for (Sensor& s : sensors_) {
      if (!s.connected || t_ns - s.last_ns <= kLeaveNs) continue;
      s.connected = false;
      sink.on_connection(s.map.sensor_id, false,
                         "tracker " + slimevr::mac_string(s.map.mac) + " left the receiver");
    }
  }
  const DecoderStats& stats() const override { return stats_; }

 private:
  struct Sensor {
    SlimeMapping map;
    DecoderCommon common;
    int id = -1;  ///< receiver id while registered
    bool connected = false;
    int64_t last_ns = 0;
    SensorTelemetry telemetry;
    bool telemetry_changed = false;
  };

  template <class F>
  static void update(Sensor& s, F&& f) {
    const SensorTelemetry before = s.telemetry;
    f(s.telemetry);
    s.telemetry_changed = s.telemetry_changed || !(before == s.telemetry);
  }

  /// The telemetry a packet carries (what it does not carry stays as it was).
  static void take_telemetry(const sh::Packet& p, SensorTelemetry& t) {
    const auto take = [](float v, float& into) {
      if (SensorTelemetry::known(v)) into = v;
    };
    take(p.battery_fraction, t.battery_fraction);
    take(p.battery_v, t.battery_v);
    take(p.temperature_c, t.temperature_c);
    take(p.rssi_dbm, t.rssi_dbm);
    if (p.type == sh::kRuntime && p.runtime_us >= 0)
      t.battery_runtime_s = static_cast<float>(static_cast<double>(p.runtime_us) * 1e-6);
    if (p.has_link_counts && p.packets_received + p.packets_lost > 0)
      t.packet_loss = static_cast<float>(p.packets_lost) /
                      static_cast<float>(p.packets_received + p.packets_lost);
    if (p.type == sh::kInfo) {
      set_named(t.board, slimevr::board_name(p.board), "board", p.board);
      set_named(t.imu, slimevr::imu_name(p.imu), "IMU", p.imu);
      set_named(t.mcu, slimevr::mcu_name(p.mcu), "MCU", p.mcu);
      char buf[48];
      std::snprintf(buf, sizeof buf, "%u.%u.%u (%04u-%02u-%02u)", p.fw_major, p.fw_minor,
                    p.fw_patch, p.fw_year, p.fw_month, p.fw_day);
      SensorTelemetry::set(t.firmware, buf);
    }
  }

  void emit(Sensor& s, const sh::Packet& p, int64_t t_ns, SampleSink& sink) {
    const Eigen::Quaterniond q(p.quat_xyzw[3], p.quat_xyzw[0], p.quat_xyzw[1], p.quat_xyzw[2]);
    const double norm = q.norm();
    if (!std::isfinite(norm) || norm < 0.5 || norm > 1.5) {
      ++stats_.implausible;
      return;
    }
    ImuSample out;
    out.q_device_sensor = q;
    out.valid = kFieldQuat;
    if (p.has_accel) {
      // Linear acceleration as over UDP: gravity put back through the tracker's orientation.
      out.acc_m_s2 = Eigen::Vector3d(p.accel_m_s2[0], p.accel_m_s2[1], p.accel_m_s2[2]) +
                     q.normalized().conjugate() * Eigen::Vector3d(0, 0, kGravity_m_s2);
      out.valid |= kFieldAcc;
    }
    s.last_ns = t_ns;
    if (!s.connected) {
      s.connected = true;
      sink.on_connection(s.map.sensor_id, true,
                         "tracker " + slimevr::mac_string(s.map.mac) + " appeared (receiver id " +
                             std::to_string(s.id) + ")");
    }
    const uint64_t before = s.common.stats.samples;
    s.common.emit_untimed(out, t_ns, sink);
    stats_.samples += s.common.stats.samples - before;
  }

  DecoderStats stats_;
  std::vector<Sensor> sensors_;  // sized once in the constructor
  std::array<sh::Packet, sh::kMaxPackets> packets_{};
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_slimevr_hid_decoder(const DeviceSpec& spec) {
  return std::make_unique<SlimeVrHidDecoder>(spec);
}

}  // namespace mocap
