// Simulated SlimeVR receiver dongle ("slimevr_hid"): 64-byte input reports of four 16-byte
// packets: a register packet (receiver id -> tracker address) for one tracker in turn, then a
// full-precision quaternion + acceleration packet (type 1) per tracker. Trackers share the truth
// motion, each a quarter second apart. Options: trackers=1..3, address=AABBCCDDEE00 (the first
// tracker's address as the SlimeVR server prints it; tracker k adds k).
#include <algorithm>
#include <stdexcept>
#include <string>

#include "mocap/drivers/slimevr_hid.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

namespace sh = slimevr_hid;

class SlimeHidEncoder final : public ProtocolEncoder {
 public:
  explicit SlimeHidEncoder(const EncoderOptions& opt) : rate_(opt.rate_hz) {
    const auto get = [&](const char* k, const char* d) {
      const auto it = opt.options.find(k);
      return it == opt.options.end() ? std::string(d) : it->second;
    };
    trackers_ = std::stoi(get("trackers", "1"));
    if (trackers_ < 1 || trackers_ > 3)
      throw std::invalid_argument("slimevr_hid: trackers must be 1..3 (one report)");
    address_ = std::stoull(get("address", "025E000000A0"), nullptr, 16);
  }

  void encode(const ImuSample& truth, std::vector<uint8_t>& out) override {
    const std::size_t start = out.size();
    out.resize(start + 64, 0);
    uint8_t* r = out.data() + start;
    const int reg = static_cast<int>(calls_++ % static_cast<uint64_t>(trackers_));
    r[0] = sh::kRegister;
    r[1] = static_cast<uint8_t>(reg + 1);  // receiver ids from 1
    const uint64_t addr = address_ + static_cast<uint64_t>(reg);
    for (int j = 0; j < 6; ++j)
      r[2 + j] = static_cast<uint8_t>(addr >> (8 * j));  // little-endian
    const Eigen::Quaterniond q = truth.q_device_sensor.normalized();
    const Eigen::Vector3d lin = truth.acc_m_s2 - q.conjugate() * Eigen::Vector3d(0, 0, 9.80665);
    for (int k = 0; k < trackers_; ++k) {
      uint8_t* p = r + 16 * (k + 1);
      p[0] = sh::kQuatAccel;
      p[1] = static_cast<uint8_t>(k + 1);
      const double qv[4] = {q.x(), q.y(), q.z(), q.w()};
      for (int j = 0; j < 4; ++j)
        put16(p + 2 + 2 * j, qv[j] * 32768.0);
      for (int j = 0; j < 3; ++j)
        put16(p + 10 + 2 * j, lin[j] * 128.0);
    }
  }
  double rate_hz() const override { return rate_; }
  std::size_t report_size() const override { return 64; }

 private:
  static void put16(uint8_t* p, double v) {
    const auto i = static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
    p[0] = static_cast<uint8_t>(i);
    p[1] = static_cast<uint8_t>(static_cast<uint16_t>(i) >> 8);
  }
  double rate_;
  int trackers_ = 1;
  uint64_t address_ = 0, calls_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_slimevr_hid_encoder(const EncoderOptions& opt) {
  return std::make_unique<SlimeHidEncoder>(opt);
}

}  // namespace mocap
