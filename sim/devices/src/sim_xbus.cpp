// Simulated Xsens MTi: streams MTData2 in measurement mode, answers GoToConfig,
// SetOutputConfiguration (echoed, rate applied), GoToMeasurement and ReqDID like the device.
#include <algorithm>
#include <cmath>

#include "mocap/drivers/xbus.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

class XbusEncoder final : public ProtocolEncoder {
 public:
  explicit XbusEncoder(const EncoderOptions& opt) : rate_(opt.rate_hz) {
    counter_ = static_cast<uint16_t>(std::stoul(enc_option(opt, "counter_start", "0")));
    time_start_ = std::stoull(enc_option(opt, "time_start_ticks", "0"));
  }

  void encode(const ImuSample& s, std::vector<uint8_t>& out) override {
    std::vector<uint8_t>& p = payload_;
    p.clear();
    const uint32_t ticks =
        static_cast<uint32_t>(time_start_ + static_cast<uint64_t>(s.t_device_ns / 100'000));
    p.insert(p.end(),
             {0x10, 0x20, 2, static_cast<uint8_t>(counter_ >> 8), static_cast<uint8_t>(counter_)});
    p.insert(p.end(),
             {0x10, 0x60, 4, static_cast<uint8_t>(ticks >> 24), static_cast<uint8_t>(ticks >> 16),
              static_cast<uint8_t>(ticks >> 8), static_cast<uint8_t>(ticks)});
    const auto& q = s.q_device_sensor;
    const double qv[4] = {q.w(), q.x(), q.y(), q.z()};
    xbus::put_floats(xbus::kQuaternion, qv, p);
    xbus::put_floats(xbus::kAcceleration, std::span(s.acc_m_s2.data(), 3), p);
    xbus::put_floats(xbus::kRateOfTurn, std::span(s.gyr_rad_s.data(), 3), p);
    const Eigen::Vector3d mag_au = s.mag_uT / 50.0;  // normalised to a ~50 uT local field
    xbus::put_floats(xbus::kMagneticField, std::span(mag_au.data(), 3), p);
    xbus::encode(xbus::kMtData2, p, out);
    ++counter_;
  }

  void handle_host_bytes(std::span<const uint8_t> in, std::vector<uint8_t>& reply) override {
    xbus::Message m;
    bool got = false;
    do {
      in = in.subspan(framer_.consume(in, m, got));
      if (!got) continue;
      switch (m.mid) {
        case xbus::kGoToConfig:
          measuring_ = false;
          xbus::encode(xbus::kGoToConfigAck, {}, reply);
          break;
        case xbus::kGoToMeasurement:
          measuring_ = true;
          xbus::encode(xbus::kGoToMeasurementAck, {}, reply);
          break;
        case xbus::kReqDid: {
          const uint8_t id[4] = {0x03, 0x70, 0x12, 0x34};
          xbus::encode(xbus::kDeviceId, id, reply);
          break;
        }
        case xbus::kSetOutputConfig: {
          if (measuring_) {  // only valid in configuration mode
            const uint8_t err = 0x04;
            xbus::encode(xbus::kError, std::span(&err, 1), reply);
            break;
          }
          double r = 0;
          for (std::size_t i = 0; i + 4 <= m.data.size(); i += 4) {
            const uint16_t f = static_cast<uint16_t>(m.data[i + 2] << 8 | m.data[i + 3]);
            if (f != 0xFFFF && f > 0) r = r > 0 ? std::min(r, double(f)) : f;
          }
          if (r > 0) rate_ = r;
          xbus::encode(xbus::kOutputConfigAck, m.data, reply);
          break;
        }
        default: {
          const uint8_t err = 0x04;  // unknown message
          xbus::encode(xbus::kError, std::span(&err, 1), reply);
        }
      }
    } while (got || !in.empty());
  }

  bool streaming() const override { return measuring_; }
  double rate_hz() const override { return rate_; }

 private:
  double rate_;
  uint16_t counter_ = 0;
  uint64_t time_start_ = 0;
  bool measuring_ = true;
  xbus::Framer framer_;
  std::vector<uint8_t> payload_;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_xbus_encoder(const EncoderOptions& opt) {
  return std::make_unique<XbusEncoder>(opt);
}

}  // namespace mocap
