// Decoder for DS4 / DualSense USB reports: one feed() = one HID report. The calibration feature
// report (read by the device at open and recorded in the raw stream) sets the scale; input
// reports give gyro/acc and the sensor timestamp (unwrapped, drift-tracked to host time).
#include <cmath>

#include "decoder_common.hpp"
#include "decoders.hpp"
#include "mocap/core/units.hpp"
#include "mocap/drivers/playstation.hpp"
#include "protocols.hpp"

namespace mocap {
namespace {

using namespace playstation;

class PlaystationDecoder final : public ProtocolDecoder {
 public:
  // Full scale: the hid-playstation ranges (2048 deg/s, 4 g over 32767).
  explicit PlaystationDecoder(const DeviceSpec& spec)
      : common_(spec, {.gyr_dps = 2048, .acc_g = 4}),
        model_(spec.protocol == "dualsense" ? Model::kDualSense : Model::kDs4),
        scale_(default_scale()),
        ts_(timestamp_modulus(model_)) {}

  void feed(std::span<const uint8_t> r, int64_t t_host_ns, SampleSink& sink) override {
    common_.stats.bytes += r.size();
    playstation::Calibration c;
    if (parse_calibration(model_, r, c)) {
      scale_ = scale_from(c);
      ++calibrations_;
      ++common_.stats.frames;
      return;
    }
    if (!parse_input(model_, r, in_)) {
      ++common_.stats.resyncs;  // not a report this decoder knows
      return;
    }
    ++common_.stats.frames;
    const int64_t ticks = ts_.next(in_.timestamp);
    const int64_t t_device_ns =
        static_cast<int64_t>(std::llround(static_cast<double>(ticks) * tick_ns(model_)));
    const int64_t dropped = first_ ? 0 : period_.update(t_device_ns - last_device_ns_);
    first_ = false;
    last_device_ns_ = t_device_ns;
    ImuSample s;
    for (int k = 0; k < 3; ++k) {
      s.gyr_rad_s[k] = in_.gyr[k] * scale_.gyr_dps_per_lsb[k] * kRadPerDeg;
      s.acc_m_s2[k] =
          (in_.acc[k] - scale_.acc_bias[k]) * scale_.acc_g_per_lsb[k] * kStandardGravity_m_s2;
    }
    s.valid = kFieldGyr | kFieldAcc;
    common_.emit(s, t_device_ns, t_host_ns, dropped, sink);
  }
  const DecoderStats& stats() const override { return common_.stats; }
  uint64_t replies(uint32_t id) const override { return id == 0xFE ? calibrations_ : 0; }

 private:
  DecoderCommon common_;
  Model model_;
  Scale scale_;
  Input in_;
  Unwrapper ts_;
  PeriodTracker period_;
  bool first_ = true;
  int64_t last_device_ns_ = 0;
  uint64_t calibrations_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_playstation_decoder(const DeviceSpec& spec) {
  return std::make_unique<PlaystationDecoder>(spec);
}

std::vector<SetupStep> playstation_setup(const DeviceSpec& spec) {
  const bool ds = spec.protocol == "dualsense";
  return {{.kind = SetupStep::kGetFeature,
           .bytes = {ds ? kCalibBt : kDs4CalibUsb},
           .feature_size = ds ? kCalib41Size : kDs4CalibUsbSize,
           .reply_id = 0xFE,  // counted by the decoder when the calibration parses
           .timeout_ms = 100,
           .what = "read calibration feature report"}};
}

}  // namespace mocap
