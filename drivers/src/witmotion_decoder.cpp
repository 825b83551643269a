// Decoder for WitMotion packets: groups one output cycle (time, acc, gyro, angle, mag, quat) into
// one sample, converts units (16 g, 2000 deg/s, 180 deg, q/32768) and maps device time.
#include <cmath>
#include <stdexcept>

#include "decoder_common.hpp"
#include "decoders.hpp"
#include "mocap/core/units.hpp"
#include "mocap/drivers/witmotion.hpp"

namespace mocap {
namespace {

class WitmotionDecoder final : public ProtocolDecoder {
 public:
  // Full scale by the wire formula: raw/32768 x 2000 deg/s and x 16 g.
  explicit WitmotionDecoder(const DeviceSpec& spec)
      : common_(spec, {.gyr_dps = 2000, .acc_g = 16}) {
    const auto order = option_string(spec, "quat_order", "wxyz");
    if (order != "wxyz" && order != "xyzw")
      throw std::invalid_argument("device " + spec.name + ": quat_order must be wxyz or xyzw");
    quat_xyzw_ = order == "xyzw";
    mag_scale_ = option_double(spec, "mag_scale_uT", 1.0);
  }

  void feed(std::span<const uint8_t> bytes, int64_t t_host_ns, SampleSink& sink) override {
    common_.stats.bytes += bytes.size();
    while (!bytes.empty()) {
      bool got = false;
      bytes = bytes.subspan(framer_.consume(bytes, pkt_, got));
      if (got) handle(t_host_ns, sink);
    }
    common_.stats.frames = framer_.frames;
    common_.stats.checksum_errors = framer_.checksum_errors;
    common_.stats.resyncs = framer_.resyncs;
  }
  const DecoderStats& stats() const override { return common_.stats; }
  uint64_t replies(uint32_t id) const override {
    return id == witmotion::kRegReply ? reg_replies_ : 0;
  }

 private:
  void handle(int64_t t_read_ns, SampleSink& sink) {
    using namespace witmotion;
    const uint8_t type = pkt_.type;
    if (type == kRegReply) {
      ++reg_replies_;
      return;
    }
    const uint16_t bit = type <= 0x5A ? rsw_bit(type) : 0;
    // The device sends a cycle's packets in ascending type order: a type not above the previous
    // one starts a new cycle, and the previous cycle's last type is where cycles end.
    if (seen_ != 0 && type <= last_type_) {
      cycle_end_ = last_type_;
      flush(t_read_ns, sink);
    } else if (seen_ == 0 && last_type_ != 0 && type > last_type_ && last_type_ == cycle_end_) {
      // More packets after the learned end (output content was changed): learn the new end;
      // this packet belonged to the sample already emitted.
      cycle_end_ = type;
      last_type_ = type;
      return;
    }
    const auto& d = pkt_.d;
    switch (type) {
      case kTime: {
        const auto b = [&](int i) {
          return static_cast<int64_t>(static_cast<uint16_t>(d[i / 2]) >> (8 * (i % 2)) & 0xFF);
        };
        // YY MM DD hh mm ss ms: time within the month (a month change is a clock restart).
        const int64_t ms = ((((b(2) - 1) * 24 + b(3)) * 60 + b(4)) * 60 + b(5)) * 1000 +
                           static_cast<uint16_t>(d[3]);
        t_device_ms_ = ms;
        break;
      }
      case kAcc:
        s_.acc_m_s2 = Eigen::Vector3d(d[0], d[1], d[2]) * (16.0 * kStandardGravity_m_s2 / 32768.0);
        s_.valid |= kFieldAcc;
        break;
      case kGyr:
        s_.gyr_rad_s = Eigen::Vector3d(d[0], d[1], d[2]) * (2000.0 * kRadPerDeg / 32768.0);
        s_.valid |= kFieldGyr;
        break;
      case kMag:
        s_.mag_uT = Eigen::Vector3d(d[0], d[1], d[2]) * mag_scale_;
        s_.valid |= kFieldMag;
        break;
      case kAngle:
        euler_ = Eigen::Vector3d(d[0], d[1], d[2]) * (M_PI / 32768.0);
        has_euler_ = true;
        break;
      case kQuat:
        s_.q_device_sensor = quat_xyzw_ ? Eigen::Quaterniond(d[3], d[0], d[1], d[2])
                                        : Eigen::Quaterniond(d[0], d[1], d[2], d[3]);
        s_.q_device_sensor.coeffs() /= 32768.0;
        s_.valid |= kFieldQuat;
        break;
      default:
        break;
    }
    seen_ |= bit;
    last_type_ = type;
    if (type == cycle_end_) flush(t_read_ns, sink);
  }

  void flush(int64_t t_read_ns, SampleSink& sink) {
    if (!s_.has(kFieldQuat) && has_euler_) {  // ZYX: R = Rz(yaw) Ry(pitch) Rx(roll)
      s_.q_device_sensor = Eigen::AngleAxisd(euler_.z(), Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(euler_.y(), Eigen::Vector3d::UnitY()) *
                           Eigen::AngleAxisd(euler_.x(), Eigen::Vector3d::UnitX());
      s_.valid |= kFieldQuat;
    }
    if (s_.valid != 0) {
      if (t_device_ms_ < 0 && last_device_ns_ >= 0 && period_.period_ns() > 0) {
        // The time packet of a timed stream was lost: the sample is one period after the last.
        t_device_ms_ = (last_device_ns_ + period_.period_ns()) / 1'000'000;
      }
      if (t_device_ms_ >= 0) {
        const int64_t t_device_ns = t_device_ms_ * 1'000'000;
        const int64_t dropped =
            last_device_ns_ >= 0 ? period_.update(t_device_ns - last_device_ns_) : 0;
        last_device_ns_ = t_device_ns;
        common_.emit(s_, t_device_ns, t_read_ns, dropped, sink);
      } else {
        common_.emit_untimed(s_, t_read_ns, sink);
      }
    }
    s_ = ImuSample{};
    seen_ = 0;
    has_euler_ = false;
    t_device_ms_ = -1;
  }

  DecoderCommon common_;
  witmotion::Framer framer_;
  witmotion::Packet pkt_;
  ImuSample s_;
  Eigen::Vector3d euler_ = Eigen::Vector3d::Zero();
  bool has_euler_ = false, quat_xyzw_ = false;
  double mag_scale_ = 1;
  uint16_t seen_ = 0;
  uint8_t last_type_ = 0, cycle_end_ = 0;
  int64_t t_device_ms_ = -1, last_device_ns_ = -1;
  PeriodTracker period_;
  uint64_t reg_replies_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_witmotion_decoder(const DeviceSpec& spec) {
  return std::make_unique<WitmotionDecoder>(spec);
}

}  // namespace mocap
