// libFuzzer target: the viewer's parser of pose JSON stream lines (--connect HOST:PORT). Any
// input must either be rejected with a message or give a finite frame.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "mocap/viewer/pose_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mocap::PoseFrame frame;
  mocap::reset_pose(frame);
  std::string error;
  const std::string_view line(reinterpret_cast<const char*>(data), size);
  if (mocap::viewer::parse_pose_json(line, frame, error)) {
    for (const auto& q : frame.q_earth_segment)
      for (float v : q)
        if (!std::isfinite(v)) std::abort();
    for (const auto& p : frame.p_earth_segment_m)
      for (float v : p)
        if (!std::isfinite(v)) std::abort();
  } else if (error.empty()) {
    std::abort();  // a rejection must say why
  }
  return 0;
}
