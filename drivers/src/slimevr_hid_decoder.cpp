// Decoder of the SlimeVR HID receiver (driver "slimevr_hid"): receiver ids bound to tracker
// addresses by the register packets, orientation samples (the trackers' own filter output, as
// over UDP) per mapped address, trackers reported appearing (first data) and leaving (3 s
// without data while the receiver keeps reporting).
#include <cmath>

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
          if (s.map.mac == mac) s.id = p.id;
        continue;
      }
      if (!p.has_quat) continue;
      for (Sensor& s : sensors_)
        if (s.id == p.id) emit(s, p, t_ns, sink);
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
  };

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
