// Simulated DualShock 4 / DualSense (USB): 64-byte input reports with the sensor timestamp,
// gyro/acc encoded through a per-unit factory calibration that the calibration feature report
// returns (so the decoder only gets truth back if it applies the calibration correctly).
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/drivers/playstation.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

using namespace playstation;

class PlaystationEncoder final : public ProtocolEncoder {
 public:
  PlaystationEncoder(const EncoderOptions& opt, bool dualsense)
      : rate_(opt.rate_hz), model_(dualsense ? Model::kDualSense : Model::kDs4) {
    // A plausible unit: small biases, asymmetric spans, speed 540 deg/s.
    cal_.gyr_bias = {4, -7, 2};
    cal_.gyr_plus = {8650, 8700, 8600};
    cal_.gyr_minus = {-8640, -8690, -8620};
    cal_.speed_plus = cal_.speed_minus = 540;
    cal_.acc_plus = {8220, 8190, 8300};
    cal_.acc_minus = {-8160, -8200, -8100};
    scale_ = scale_from(cal_);
  }

  void encode(const ImuSample& s, std::vector<uint8_t>& out) override {
    const std::size_t o = out.size();
    out.resize(o + kInputSize, 0);
    std::vector<uint8_t> r(kInputSize, 0);
    r[0] = kInputUsb;
    for (int i = 1; i <= 4; ++i)
      r[i] = 0x80;  // sticks centred
    const double ticks = static_cast<double>(s.t_device_ns) / tick_ns(model_);
    const uint64_t ts = static_cast<uint64_t>(std::llround(ticks)) % timestamp_modulus(model_);
    std::array<int16_t, 3> g{}, a{};
    for (int k = 0; k < 3; ++k) {
      g[k] = sat16(s.gyr_rad_s[k] * kDegPerRad / scale_.gyr_dps_per_lsb[k]);
      a[k] = sat16(s.acc_m_s2[k] / 9.80665 / scale_.acc_g_per_lsb[k] + scale_.acc_bias[k]);
    }
    if (model_ == Model::kDs4) {
      r[7] = static_cast<uint8_t>((seq_ & 0x3F) << 2);
      put_le16(r, 10, static_cast<int>(ts));
      r[12] = 25;
      for (int k = 0; k < 3; ++k)
        put_le16(r, 13 + 2 * k, g[k]), put_le16(r, 19 + 2 * k, a[k]);
      r[30] = 0x1B;  // battery, cable
    } else {
      r[7] = seq_;
      for (int k = 0; k < 3; ++k)
        put_le16(r, 16 + 2 * k, g[k]), put_le16(r, 22 + 2 * k, a[k]);
      for (int b = 0; b < 4; ++b)
        r[28 + b] = static_cast<uint8_t>(ts >> (8 * b));
    }
    ++seq_;
    std::copy(r.begin(), r.end(), out.begin() + static_cast<std::ptrdiff_t>(o));
  }

  bool feature_report(uint8_t id, std::vector<uint8_t>& out) override {
    const bool ds4_usb = model_ == Model::kDs4 && id == kDs4CalibUsb;
    const bool ds_usb = model_ == Model::kDualSense && id == kCalibBt;
    if (!ds4_usb && !ds_usb) return false;
    out.assign(ds4_usb ? kDs4CalibUsbSize : kCalib41Size, 0);
    out[0] = id;
    for (int k = 0; k < 3; ++k) {
      put_le16(out, 1 + 2 * k, cal_.gyr_bias[k]);
      put_le16(out, 7 + 4 * k, cal_.gyr_plus[k]);
      put_le16(out, 9 + 4 * k, cal_.gyr_minus[k]);
      put_le16(out, 23 + 4 * k, cal_.acc_plus[k]);
      put_le16(out, 25 + 4 * k, cal_.acc_minus[k]);
    }
    put_le16(out, 19, cal_.speed_plus);
    put_le16(out, 21, cal_.speed_minus);
    return true;
  }

  void unsolicited(std::vector<uint8_t>& out) override {
    feature_report(model_ == Model::kDs4 ? kDs4CalibUsb : kCalibBt, out);
  }
  double rate_hz() const override { return rate_; }
  std::size_t report_size() const override { return kInputSize; }

 private:
  double rate_;
  Model model_;
  playstation::Calibration cal_;
  Scale scale_;
  uint8_t seq_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_playstation_encoder(const EncoderOptions& opt,
                                                          bool dualsense) {
  return std::make_unique<PlaystationEncoder>(opt, dualsense);
}

}  // namespace mocap
