// Decoder for Xsens MTi MTData2: packet counter -> drops, SampleTimeFine (10 kHz, wrapping at
// 2^32 or once a day) -> device time, m/s^2 / rad/s / normalised field / quaternion (w first).
#include <cmath>
#include <map>
#include <stdexcept>

#include "decoder_common.hpp"
#include "decoders.hpp"
#include "mocap/drivers/xbus.hpp"
#include "protocols.hpp"

namespace mocap {
namespace {

class XbusDecoder final : public ProtocolDecoder {
 public:
  // The widest MTi ranges (MTi 1-series: +-2000 deg/s, +-16 g); options narrow them per model.
  explicit XbusDecoder(const DeviceSpec& spec) : common_(spec, {.gyr_dps = 2000, .acc_g = 16}) {
    const auto wrap = option_string(spec, "time_wrap", "2^32");
    if (wrap == "day")
      time_ = Unwrapper(864'000'000);
    else if (wrap == "2^32")
      time_ = Unwrapper(uint64_t{1} << 32);
    else
      throw std::invalid_argument("device " + spec.name + ": time_wrap must be 2^32 or day");
    mag_scale_ = option_double(spec, "mag_scale_uT", 1.0);
  }

  void feed(std::span<const uint8_t> bytes, int64_t t_host_ns, SampleSink& sink) override {
    common_.stats.bytes += bytes.size();
    bool got = false;
    do {
      bytes = bytes.subspan(framer_.consume(bytes, msg_, got));
      if (got) handle(t_host_ns, sink);
    } while (got || !bytes.empty());
    common_.stats.frames = framer_.frames;
    common_.stats.checksum_errors = framer_.checksum_errors;
    common_.stats.resyncs = framer_.resyncs + malformed_;
  }
  const DecoderStats& stats() const override { return common_.stats; }
  uint64_t replies(uint32_t id) const override { return id < 256 ? replies_[id] : 0; }

 private:
  void handle(int64_t t_read_ns, SampleSink& sink) {
    ++replies_[msg_.mid];
    if (msg_.mid != xbus::kMtData2) return;
    if (!xbus::parse_mtdata2(msg_.data, d_)) {
      ++malformed_;
      return;
    }
    ImuSample s;
    if (d_.has_acc) s.acc_m_s2 = {d_.acc[0], d_.acc[1], d_.acc[2]}, s.valid |= kFieldAcc;
    if (d_.has_gyr) s.gyr_rad_s = {d_.gyr[0], d_.gyr[1], d_.gyr[2]}, s.valid |= kFieldGyr;
    if (d_.has_mag) {
      s.mag_uT = Eigen::Vector3d(d_.mag[0], d_.mag[1], d_.mag[2]) * mag_scale_;
      s.valid |= kFieldMag;
    }
    if (d_.has_quat) {
      const Eigen::Quaterniond q(d_.quat[0], d_.quat[1], d_.quat[2], d_.quat[3]);
      // The data id's coordinate bits (0x000C) name the earth frame the quaternion maps the
      // sensor into: turned into ENU here, the frame every sample carries.
      switch (d_.quat_coord) {
        case 0x0:  // ENU (0x2010)
          s.q_device_sensor = q, s.valid |= kFieldQuat;
          break;
        case 0x4:  // NED (0x2014): E = y_ned, N = x_ned, U = -z_ned
          s.q_device_sensor = enu_from_ned() * q, s.valid |= kFieldQuat;
          break;
        case 0x8:  // NWU (0x2018): E = -y_nwu, N = x_nwu, U = z_nwu
          s.q_device_sensor = enu_from_nwu() * q, s.valid |= kFieldQuat;
          break;
        default:  // reserved coordinate bits: the quaternion is dropped, counted as malformed
          ++malformed_;
          break;
      }
    }
    int64_t dropped = 0;
    if (d_.has_counter) {
      const bool first = !counter_.started();
      counter_.next(d_.counter);
      if (!first) {
        const CounterGap g = counter_gap(counter_.last_step(), 30000);
        dropped = g.reset ? 0 : g.dropped;
      }
    }
    if (d_.has_time) {
      const int64_t ticks = time_.next(d_.time_fine);
      common_.emit(s, ticks * 100'000, t_read_ns, dropped, sink);
    } else {
      common_.emit_untimed(s, t_read_ns, sink);
    }
  }

  static Eigen::Quaterniond enu_from_ned() {
    const double h = std::sqrt(0.5);  // 180 deg about (1, 1, 0) / sqrt(2)
    return Eigen::Quaterniond(0, h, h, 0);
  }
  static Eigen::Quaterniond enu_from_nwu() {
    const double h = std::sqrt(0.5);  // +90 deg about z
    return Eigen::Quaterniond(h, 0, 0, h);
  }

  DecoderCommon common_;
  xbus::Framer framer_;
  xbus::Message msg_;
  xbus::MtData2 d_;
  Unwrapper counter_{65536}, time_;
  double mag_scale_ = 1;
  std::array<uint64_t, 256> replies_{};
  uint64_t malformed_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_xbus_decoder(const DeviceSpec& spec) {
  return std::make_unique<XbusDecoder>(spec);
}

std::vector<SetupStep> xbus_setup(const DeviceSpec& spec) {
  std::vector<SetupStep> steps;
  if (option_string(spec, "configure", "1") == "0") return steps;
  auto msg = [](uint8_t mid, std::vector<uint8_t> payload, uint8_t reply, const char* what) {
    // Five attempts: the device may be streaming and miss the first GoToConfig.
    SetupStep s{.reply_id = reply, .timeout_ms = 300, .attempts = 5, .what = what};
    xbus::encode(mid, payload, s.bytes);
    return s;
  };
  const uint16_t hz = static_cast<uint16_t>(spec.rate_hz > 0 ? spec.rate_hz : 100);
  std::vector<uint8_t> cfg;
  auto item = [&](uint16_t id, uint16_t f) {
    for (uint16_t v : {id, f})
      cfg.push_back(static_cast<uint8_t>(v >> 8)), cfg.push_back(static_cast<uint8_t>(v));
  };
  item(xbus::kPacketCounter, 0xFFFF);
  item(xbus::kSampleTimeFine, 0xFFFF);
  item(xbus::kQuaternion, hz);
  item(xbus::kAcceleration, hz);
  item(xbus::kRateOfTurn, hz);
  item(xbus::kMagneticField, hz);
  steps.push_back(msg(xbus::kGoToConfig, {}, xbus::kGoToConfigAck, "GoToConfig"));
  steps.push_back(
      msg(xbus::kSetOutputConfig, cfg, xbus::kOutputConfigAck, "SetOutputConfiguration"));
  steps.push_back(msg(xbus::kGoToMeasurement, {}, xbus::kGoToMeasurementAck, "GoToMeasurement"));
  return steps;
}

}  // namespace mocap
