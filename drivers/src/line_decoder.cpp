// Decoder for the DIY line protocol: declared units -> SI, unwrapped device time -> host time,
// drops inferred from gaps in the device time.
#include <cmath>
#include <stdexcept>

#include "decoder_common.hpp"
#include "decoders.hpp"
#include "mocap/drivers/line_protocol.hpp"

namespace mocap {
namespace {

class LineDecoder final : public ProtocolDecoder {
 public:
  explicit LineDecoder(const DeviceSpec& spec) : common_(spec) {
    std::string err;
    const auto it = spec.options.find("units");
    if (it != spec.options.end() && !line::parse_units(it->second, units_, err))
      throw std::invalid_argument("device " + spec.name + ": " + err);
    unwrap_ = Unwrapper(modulus());
  }

  void feed(std::span<const uint8_t> bytes, int64_t t_host_ns, SampleSink& sink) override {
    common_.stats.bytes += bytes.size();
    while (!bytes.empty()) {
      bool got = false;
      bytes = bytes.subspan(parser_.consume(bytes, rec_, got));
      if (got) handle(t_host_ns, sink);
    }
    common_.stats.frames = parser_.frames;
    common_.stats.checksum_errors = parser_.checksum_errors;
    common_.stats.resyncs = parser_.resyncs + bad_headers_;
  }
  const DecoderStats& stats() const override { return common_.stats; }

 private:
  uint64_t modulus() const { return units_.wrap_bits >= 64 ? 0 : uint64_t{1} << units_.wrap_bits; }

  void handle(int64_t t_read_ns, SampleSink& sink) {
    if (rec_.kind == line::Record::kUnits) {
      std::string err;
      const int old_wrap = units_.wrap_bits;
      if (!line::parse_units(rec_.header, units_, err)) ++bad_headers_;
      if (units_.wrap_bits != old_wrap) unwrap_ = Unwrapper(modulus());
      return;
    }
    if (rec_.t < 0 || rec_.t > 1.8e19) {
      ++bad_headers_;
      return;
    }
    // The whole part is the counter (it wraps at 2^wrap_bits, e.g. micros()); the fraction is
    // kept in every unit (t=s 12.51 is 12 510 000 000 ns, t=ms 1002.5 is 1 002 500 000 ns).
    const double whole = std::floor(rec_.t);
    const double frac = rec_.t - whole;
    const int64_t ticks = unwrap_.next(static_cast<uint64_t>(whole));
    const auto per_tick = static_cast<int64_t>(units_.t_to_ns);  // 1, 1e3, 1e6 or 1e9: exact
    if (!(std::fabs(static_cast<double>(ticks) * units_.t_to_ns) < 4e18)) {
      ++bad_headers_;  // beyond any real clock (and int64): not a sample
      return;
    }
    const int64_t t_device_ns = ticks * per_tick + std::llround(frac * units_.t_to_ns);
    const int64_t dropped = period_.update(t_device_ns - last_device_ns_);
    last_device_ns_ = t_device_ns;
    ImuSample s;
    const auto& v = rec_.v;
    s.acc_m_s2 = Eigen::Vector3d(v[0], v[1], v[2]) * units_.acc_to_m_s2;
    s.gyr_rad_s = Eigen::Vector3d(v[3], v[4], v[5]) * units_.gyr_to_rad_s;
    s.mag_uT = Eigen::Vector3d(v[6], v[7], v[8]) * units_.mag_to_uT;
    s.valid = kFieldAcc | kFieldGyr | kFieldMag;
    common_.emit(s, t_device_ns, t_read_ns, dropped, sink);
  }

  DecoderCommon common_;
  line::Parser parser_;
  line::Record rec_;
  line::Units units_;
  Unwrapper unwrap_;
  PeriodTracker period_;
  int64_t last_device_ns_ = 0;
  uint64_t bad_headers_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolDecoder> make_line_decoder(const DeviceSpec& spec) {
  return std::make_unique<LineDecoder>(spec);
}

}  // namespace mocap
