// Decoder for Joy-Con / Pro Controller USB reports (one feed() = one report): SPI calibration
// replies set the scale; 0x30 reports give three samples each (oldest first, ~5 ms apart) timed
// from the report timer byte; the right Joy-Con's y/z are negated to the left's frame.
#include <cmath>
#include <stdexcept>

#include "decoder_common.hpp"
#include "decoders.hpp"
#include "mocap/core/units.hpp"
#include "mocap/drivers/joycon.hpp"
#include "protocols.hpp"

namespace mocap {
namespace {

using namespace joycon;

class JoyconDecoder final : public ProtocolDecoder {
 public:
  // Full scale as decoded: +-8 g (4096 LSB/g) and 32767 / 14.247 = 2300 deg/s (LSM6DS3 at
  // +-2000 deg/s read with hid-nintendo's 15 % margin).
  explicit JoyconDecoder(const DeviceSpec& spec) : common_(spec, {.gyr_dps = 2300, .acc_g = 8}) {
    const auto side = option_string(spec, "side", "left");
    if (side != "left" && side != "right" && side != "pro")
      throw std::invalid_argument("device " + spec.name + ": side must be left, right or pro");
    yz_sign_ = side == "right" ? -1 : 1;
    tick_ns_ = static_cast<int64_t>(option_double(spec, "timer_tick_us", 5000) * 1000);
  }

  void feed(std::span<const uint8_t> r, int64_t t_host_ns, SampleSink& sink) override {
    common_.stats.bytes += r.size();
    if (r.size() >= 2 && r[0] == kUsbReply) {
      ++replies_[0x100 | r[1]];
      ++common_.stats.frames;
      return;
    }
    Reply rep;
    if (parse_reply(r, rep)) {
      ++replies_[rep.subcmd];
      ++common_.stats.frames;
      SpiData spi;
      if (parse_spi_reply(rep, spi)) take_calibration(spi);
      return;
    }
    if (!parse_full(r, full_)) {
      ++common_.stats.resyncs;
      return;
    }
    ++common_.stats.frames;
    // Until the factory calibration has been read, samples would be off by the unit's offsets:
    // hold them back (for at most kMaxUncalibrated reports, then fall back to nominal scales).
    if (!calibrated_ && ++uncalibrated_reports_ <= kMaxUncalibrated) return;
    const int64_t t_report_ns = timer_.next(full_.timer) * tick_ns_;
    const int64_t reports_missing = first_ ? 0 : period_.update(t_report_ns - last_report_ns_);
    first_ = false;
    last_report_ns_ = t_report_ns;
    for (int i = 0; i < 3; ++i) {
      ImuSample s;
      const auto& m = full_.imu[i];
      for (int k = 0; k < 3; ++k) {
        const double sign = k == 0 ? 1.0 : yz_sign_;
        s.acc_m_s2[k] = sign * acc_g(cal_, k, m.acc[k]) * kStandardGravity_m_s2;
        s.gyr_rad_s[k] = sign * gyr_dps(cal_, k, m.gyr[k]) * kRadPerDeg;
      }
      s.valid = kFieldAcc | kFieldGyr;
      common_.emit(s, t_report_ns - (2 - i) * kImuSpacingNs, t_host_ns,
                   i == 0 ? reports_missing * 3 : 0, sink);
    }
  }
  const DecoderStats& stats() const override { return common_.stats; }
  uint64_t replies(uint32_t id) const override { return id < replies_.size() ? replies_[id] : 0; }

 private:
  // The user calibration (magic at 0x8026) wins over the factory one (0x6020) whatever the order
  // of the replies, as in Linux hid-nintendo and SDL.
  void take_calibration(const SpiData& spi) {
    if (spi.address == kSpiImuUserCalib && spi.bytes.size() >= kImuUserReadSize) {
      if (spi.bytes[0] == kUserCalibMagic0 && spi.bytes[1] == kUserCalibMagic1) {
        cal_ = parse_calibration(spi.bytes.subspan(2).first<kImuCalibSize>());
        user_cal_ = calibrated_ = true;
      }
    } else if (spi.address == kSpiImuFactoryCalib && spi.bytes.size() >= kImuCalibSize &&
               !user_cal_) {
      cal_ = parse_calibration(spi.bytes.first<kImuCalibSize>());
      calibrated_ = true;
    }
  }

  DecoderCommon common_;
  joycon::Calibration cal_;
  FullReport full_;
  Unwrapper timer_{256};
  PeriodTracker period_;
  bool first_ = true;
  int64_t last_report_ns_ = 0, tick_ns_ = 5'000'000;
  double yz_sign_ = 1;
  std::array<uint64_t, 0x200> replies_{};
  static constexpr int kMaxUncalibrated = 200;
  bool calibrated_ = false, user_cal_ = false;
  int uncalibrated_reports_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_joycon_decoder(const DeviceSpec& spec) {
  return std::make_unique<JoyconDecoder>(spec);
}

std::vector<SetupStep> joycon_setup(const DeviceSpec& spec) {
  std::vector<SetupStep> steps;
  auto step = [&](std::vector<uint8_t> bytes, int64_t reply, const char* what) {
    steps.push_back({.bytes = std::move(bytes),
                     .reply_id = reply,
                     .timeout_ms = reply >= 0 ? 300 : 20,
                     .what = what});
  };
  if (option_string(spec, "usb_handshake", "1") == "1") {  // Pro Controller / Charging Grip on USB
    step({kUsbCmd, 0x02}, 0x102, "USB handshake");
    step({kUsbCmd, 0x03}, 0x103, "USB 3 Mbit");
    step({kUsbCmd, 0x02}, 0x102, "USB handshake");
    step({kUsbCmd, 0x04}, -1, "USB force (no timeout)");
  }
  uint8_t n = 0;
  step(spi_read(n++, kSpiImuUserCalib, kImuUserReadSize), kSubSpiRead, "read IMU user calibration");
  step(spi_read(n++, kSpiImuFactoryCalib, kImuCalibSize), kSubSpiRead,
       "read IMU factory calibration");
  const uint8_t full = 0x30, on = 0x01;
  step(subcommand(n++, kSubReportMode, std::span(&full, 1)), kSubReportMode,
       "standard full report mode");
  step(subcommand(n++, kSubEnableImu, std::span(&on, 1)), kSubEnableImu, "enable IMU");
  return steps;
}

}  // namespace mocap
