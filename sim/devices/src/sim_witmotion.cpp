// Simulated WitMotion WT901: emits the packets enabled in its RSW register at its RRATE, and
// answers unlock / RSW / RRATE / BAUD writes and register reads like the device (writes need
// the unlock key first, as on current firmware).
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/drivers/witmotion.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

using namespace witmotion;

class WitmotionEncoder final : public ProtocolEncoder {
 public:
  explicit WitmotionEncoder(const EncoderOptions& opt) {
    quat_xyzw_ = enc_option(opt, "quat_order", "wxyz") == "xyzw";
    regs_[kRegRsw] = static_cast<uint16_t>(std::stoul(enc_option(opt, "rsw", "30")));  // 0x1E
    regs_[kRegRate] = rate_code(opt.rate_hz);
    regs_[kRegBaud] = baud_code(9600);
  }

  void encode(const ImuSample& s, std::vector<uint8_t>& out) override {
    const uint16_t rsw = regs_[kRegRsw];
    Packet p;
    if (rsw & rsw_bit(kTime)) {
      const int64_t ms = s.t_device_ns / 1'000'000;
      const int64_t sec = ms / 1000;
      const int day = static_cast<int>(sec / 86400) + 1, hh = static_cast<int>(sec / 3600 % 24),
                mm = static_cast<int>(sec / 60 % 60), ss = static_cast<int>(sec % 60);
      p.type = kTime;
      p.d = {static_cast<int16_t>(24 | (1 << 8)), static_cast<int16_t>(day | (hh << 8)),
             static_cast<int16_t>(mm | (ss << 8)), static_cast<int16_t>(ms % 1000)};
      witmotion::encode(p, out);
    }
    if (rsw & rsw_bit(kAcc)) put(kAcc, s.acc_m_s2 * (32768.0 / (16 * kStandardGravity_m_s2)), out);
    if (rsw & rsw_bit(kGyr)) put(kGyr, s.gyr_rad_s * kDegPerRad * (32768.0 / 2000), out);
    const auto& q = s.q_device_sensor;
    if (rsw & rsw_bit(kAngle)) {
      const Eigen::Matrix3d r = q.toRotationMatrix();
      const double roll = std::atan2(r(2, 1), r(2, 2));
      const double pitch = std::asin(std::fmax(-1.0, std::fmin(1.0, -r(2, 0))));
      const double yaw = std::atan2(r(1, 0), r(0, 0));
      put(kAngle, Eigen::Vector3d(roll, pitch, yaw) * (32768.0 / M_PI), out);
    }
    if (rsw & rsw_bit(kMag)) put(kMag, s.mag_uT, out);
    if (rsw & rsw_bit(kQuat)) {
      p.type = kQuat;
      const Eigen::Vector4d v = quat_xyzw_ ? Eigen::Vector4d(q.x(), q.y(), q.z(), q.w())
                                           : Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
      for (int k = 0; k < 4; ++k)
        p.d[k] = sat16(v[k] * 32768.0);
      witmotion::encode(p, out);
    }
  }

  void handle_host_bytes(std::span<const uint8_t> in, std::vector<uint8_t>& reply) override {
    for (uint8_t b : in) {
      if (n_ == 0 && b != 0xFF) continue;
      if (n_ == 1 && b != 0xAA) {
        n_ = b == 0xFF ? 1 : 0;
        continue;
      }
      cmd_[n_++] = b;
      if (n_ < 5) continue;
      n_ = 0;
      const uint8_t reg = cmd_[2];
      const uint16_t value = static_cast<uint16_t>(cmd_[3] | (cmd_[4] << 8));
      if (reg == kRegKey) {
        unlocked_ = value == kUnlockKey;
      } else if (reg == kRegRead) {
        Packet p;
        p.type = kRegReply;
        for (int k = 0; k < 4; ++k)
          p.d[k] = static_cast<int16_t>(regs_[(cmd_[3] + k) & 0xFF]);
        witmotion::encode(p, reply);
      } else if (unlocked_ && reg != kRegSave) {
        regs_[reg] = value;
      }
    }
  }

  double rate_hz() const override {
    const double r = witmotion::rate_hz(static_cast<uint8_t>(regs_[kRegRate]));
    return r > 0 ? r : 10;
  }

 private:
  void put(uint8_t type, const Eigen::Vector3d& raw, std::vector<uint8_t>& out) {
    Packet p;
    p.type = type;
    for (int k = 0; k < 3; ++k)
      p.d[k] = sat16(raw[k]);
    p.d[3] = 3650;  // 36.50 degC
    witmotion::encode(p, out);
  }
  std::array<uint16_t, 256> regs_{};
  std::array<uint8_t, 5> cmd_{};
  int n_ = 0;
  bool unlocked_ = false, quat_xyzw_ = false;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_witmotion_encoder(const EncoderOptions& opt) {
  return std::make_unique<WitmotionEncoder>(opt);
}

}  // namespace mocap
