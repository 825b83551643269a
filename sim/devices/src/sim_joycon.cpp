// Simulated Joy-Con / Pro Controller (USB): answers the USB handshake (0x80 xx -> 0x81 xx) and
// subcommands (SPI reads of its factory and user calibration, report mode, IMU enable) with 0x21
// replies, then sends 0x30 reports carrying three IMU samples each through that calibration.
#include <cmath>
#include <deque>

#include "mocap/core/units.hpp"
#include "mocap/drivers/joycon.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

using namespace joycon;

class JoyconEncoder final : public ProtocolEncoder {
 public:
  explicit JoyconEncoder(const EncoderOptions& opt) : rate_(opt.rate_hz) {
    cal_.acc_origin = {30, -20, 15};
    cal_.acc_sens = {16384, 16300, 16450};
    cal_.gyr_offset = {12, -8, 5};
    cal_.gyr_sens = {13371, 13300, 13400};
    // options.user_cal = "1": a user calibration (magic at 0x8026) that differs from the
    // factory one; the IMU then reads through it (as after the console's recalibration).
    if (enc_option(opt, "user_cal", "0") == "1") {
      factory_ = cal_;
      cal_.acc_origin = {-60, 45, -25};
      cal_.acc_sens = {16500, 16200, 16380};
      cal_.gyr_offset = {-30, 22, -14};
      cal_.gyr_sens = {13500, 13250, 13371};
      user_ = true;
    } else {
      factory_ = cal_;
    }
    yz_sign_ = enc_option(opt, "side", "left") == "right" ? -1 : 1;
    // Standalone captures (no host) start streaming; a live sim waits for the host's set-up.
    if (enc_option(opt, "wait_for_host", "0") == "0") mode_ = 0x30, imu_ = true;
  }

  void encode(const ImuSample& s, std::vector<uint8_t>& out) override {
    ImuRaw& m = pending_[n_pending_];
    for (int k = 0; k < 3; ++k) {
      const double sign = k == 0 ? 1.0 : yz_sign_;
      const double g = sign * s.acc_m_s2[k] / 9.80665;
      const double dps = sign * s.gyr_rad_s[k] * kDegPerRad;
      m.acc[k] =
          imu_ ? sat16(g * 4096.0 * (cal_.acc_sens[k] - cal_.acc_origin[k]) / cal_.acc_sens[k]) : 0;
      m.gyr[k] =
          imu_ ? sat16(dps * 14.247 * (cal_.gyr_sens[k] - cal_.gyr_offset[k]) / cal_.gyr_sens[k] +
                       cal_.gyr_offset[k])
               : 0;
    }
    if (++n_pending_ < 3) return;
    n_pending_ = 0;
    // The timer is the report's device time (newest sample) in 5 ms ticks.
    const uint8_t timer = static_cast<uint8_t>(s.t_device_ns / kImuSpacingNs);
    std::vector<uint8_t> r(kReportSize, 0);
    r[0] = kInputFull;
    r[1] = timer;
    r[2] = 0x8E;  // battery full, USB powered
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        put_le16(r, 13 + 12 * i + 2 * k, pending_[i].acc[k]),
            put_le16(r, 19 + 12 * i + 2 * k, pending_[i].gyr[k]);
    out.insert(out.end(), r.begin(), r.end());
  }

  void handle_host_bytes(std::span<const uint8_t> in, std::vector<uint8_t>& reply) override {
    if (in.size() >= 2 && in[0] == kUsbCmd) {
      if (in[1] == 0x04) return;  // force USB: no reply
      std::vector<uint8_t> r(kReportSize, 0);
      r[0] = kUsbReply;
      r[1] = in[1];
      reply.insert(reply.end(), r.begin(), r.end());
      return;
    }
    if (in.size() < 11 || in[0] != kOutputSubcmd) return;
    const uint8_t id = in[10];
    std::vector<uint8_t> r(kReportSize, 0);
    r[0] = kInputReply;
    r[13] = 0x80;
    r[14] = id;
    if (id == kSubSpiRead && in.size() >= 16) {
      const uint32_t addr =
          in[11] | in[12] << 8 | in[13] << 16 | static_cast<uint32_t>(in[14]) << 24;
      const uint8_t len = std::min<uint8_t>(in[15], 0x1D);
      r[13] = 0x90;
      std::copy(in.begin() + 11, in.begin() + 16, r.begin() + 15);
      if (addr == kSpiImuFactoryCalib && len >= kImuCalibSize)
        encode_calibration(factory_, std::span(r).subspan(20).first<kImuCalibSize>());
      if (addr == kSpiImuUserCalib && len >= kImuUserReadSize) {
        std::fill(r.begin() + 20, r.begin() + 20 + len, uint8_t{0xFF});  // erased flash
        if (user_) {
          r[20] = kUserCalibMagic0, r[21] = kUserCalibMagic1;
          encode_calibration(cal_, std::span(r).subspan(22).first<kImuCalibSize>());
        }
      }
    } else if (id == kSubReportMode && in.size() >= 12) {
      mode_ = in[11];
    } else if (id == kSubEnableImu && in.size() >= 12) {
      imu_ = in[11] != 0;
    }
    reply.insert(reply.end(), r.begin(), r.end());
  }

  void unsolicited(std::vector<uint8_t>& out) override {
    // One report per call: the calibration the decoder will use.
    if (user_)
      handle_host_bytes(spi_read(0, kSpiImuUserCalib, kImuUserReadSize), out);
    else
      handle_host_bytes(spi_read(0, kSpiImuFactoryCalib, kImuCalibSize), out);
  }
  bool streaming() const override { return mode_ == 0x30; }
  double rate_hz() const override { return rate_; }
  std::size_t report_size() const override { return kReportSize; }

 private:
  double rate_;
  joycon::Calibration cal_;      ///< the one the IMU reads through (user if set, else factory)
  joycon::Calibration factory_;  ///< at SPI 0x6020
  bool user_ = false;            ///< a user calibration at 0x8026
  double yz_sign_ = 1;
  uint8_t mode_ = 0x3F;
  bool imu_ = false;
  std::array<ImuRaw, 3> pending_{};
  int n_pending_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_joycon_encoder(const EncoderOptions& opt) {
  return std::make_unique<JoyconEncoder>(opt);
}

}  // namespace mocap
