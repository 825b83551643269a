// Simulated DIY line-protocol sensor: a units header, then one text line per sample.
#include <stdexcept>

#include "mocap/drivers/line_protocol.hpp"
#include "sim_common.hpp"

namespace mocap {
namespace {

class LineEncoder final : public ProtocolEncoder {
 public:
  explicit LineEncoder(const EncoderOptions& opt) : rate_(opt.rate_hz) {
    decl_ = enc_option(opt, "units", "t=us acc=g gyr=dps mag=uT wrap=32");
    std::string err;
    if (!line::parse_units(decl_, units_, err)) throw std::invalid_argument(err);
    checksum_ = enc_option(opt, "checksum", "1") == "1";
  }
  void encode(const ImuSample& s, std::vector<uint8_t>& out) override {
    if (n_++ % 100 == 0) {  // the header repeats so a reader that joins late learns the units
      const std::string h = "#units " + decl_ + "\n";
      out.insert(out.end(), h.begin(), h.end());
    }
    const double t = static_cast<double>(s.t_device_ns) / units_.t_to_ns;
    const uint64_t mask =
        units_.wrap_bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << units_.wrap_bits) - 1;
    std::array<double, 9> v;
    for (int k = 0; k < 3; ++k) {
      v[k] = s.acc_m_s2[k] / units_.acc_to_m_s2;
      v[3 + k] = s.gyr_rad_s[k] / units_.gyr_to_rad_s;
      v[6 + k] = s.mag_uT[k] / units_.mag_to_uT;
    }
    const std::string line =
        line::format_line(static_cast<uint64_t>(std::llround(t)) & mask, v, checksum_);
    out.insert(out.end(), line.begin(), line.end());
  }
  double rate_hz() const override { return rate_; }

 private:
  double rate_;
  std::string decl_;
  line::Units units_;
  bool checksum_ = true;
  uint64_t n_ = 0;
};

}  // namespace

std::unique_ptr<ProtocolEncoder> make_line_encoder(const EncoderOptions& opt) {
  return std::make_unique<LineEncoder>(opt);
}

}  // namespace mocap
