// Helpers shared by the simulated-device encoders (internal).
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "mocap/devsim/sim_encoder.hpp"

namespace mocap {

/// Rounds and saturates to int16 (a real sensor clips at full scale).
inline int16_t sat16(double v) {
  if (!(v == v)) return 0;
  return static_cast<int16_t>(std::lround(std::fmin(32767.0, std::fmax(-32768.0, v))));
}
inline void put_le16(std::vector<uint8_t>& b, std::size_t off, int v) {
  b[off] = static_cast<uint8_t>(v & 0xFF);
  b[off + 1] = static_cast<uint8_t>((v >> 8) & 0xFF);
}
inline std::string enc_option(const EncoderOptions& o, const char* key, const char* fallback) {
  const auto it = o.options.find(key);
  return it == o.options.end() ? fallback : it->second;
}

std::unique_ptr<ProtocolEncoder> make_line_encoder(const EncoderOptions& opt);
std::unique_ptr<ProtocolEncoder> make_witmotion_encoder(const EncoderOptions& opt);
std::unique_ptr<ProtocolEncoder> make_xbus_encoder(const EncoderOptions& opt);
std::unique_ptr<ProtocolEncoder> make_playstation_encoder(const EncoderOptions& opt,
                                                          bool dualsense);
std::unique_ptr<ProtocolEncoder> make_joycon_encoder(const EncoderOptions& opt);
std::unique_ptr<ProtocolEncoder> make_slimevr_hid_encoder(const EncoderOptions& opt);

}  // namespace mocap
