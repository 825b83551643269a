// libFuzzer target: the CSV sample importer of `mocap replay` and `mocap gyro-scale`. Any bytes
// give samples or an error naming the line; every emitted sample is finite, in time order, with
// a known sensor; the gyro scale estimate of what was read is finite and positive.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>
#include <vector>

#include "mocap/daemon/sample_csv.hpp"
#include "mocap/filter/gyro_scale.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  mocap::daemon::SampleCsvParser p("fuzz.csv");
  mocap::ImuSample s;
  int64_t last_t = INT64_MIN;
  std::vector<mocap::ImuSample> samples;
  while (!text.empty()) {
    const size_t nl = text.find('\n');
    const std::string_view line = text.substr(0, nl);
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    const int r = p.feed_line(line, s);
    if (r < 0) {
      if (p.error().empty()) std::abort();
      break;
    }
    if (r == 1) {
      if (s.sensor_id >= p.sensors().size() || s.t_host_ns < last_t) std::abort();
      if (!s.gyr_rad_s.allFinite() || !s.acc_m_s2.allFinite() || !s.mag_uT.allFinite())
        std::abort();
      last_t = s.t_host_ns;
      samples.push_back(s);
    }
  }
  const mocap::GyroScaleResult g = mocap::estimate_gyro_scale(samples);
  for (const auto& a : g.axis)
    if (!std::isfinite(a.scale) || a.scale <= 0) std::abort();
  return 0;
}
