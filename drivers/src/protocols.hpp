// The table of supported protocols (internal): how to build each decoder, which transport and
// serial settings it uses by default, and the host commands a device needs after opening.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "decoders.hpp"

namespace mocap {

/// One host action after the transport opens (configuration, calibration read).
struct SetupStep {
  enum Kind { kWrite, kGetFeature, kSetBaud, kPause } kind = kWrite;
  std::vector<uint8_t> bytes;  ///< kWrite: bytes to send; kGetFeature: {report id} and size
  int baud = 0;                ///< kSetBaud: the host side follows the device to this baud
  std::size_t feature_size = 0;
  int64_t reply_id = -1;  ///< wait until the decoder counts a reply with this id
  int timeout_ms = 250;   ///< reply wait (or pause length)
  int attempts = 3;       ///< sends before giving up on a reply
  const char* what = "";  ///< for logs
};

struct ProtocolInfo {
  std::string_view name;
  enum Transport { kSerial, kHid, kUdp } transport = kSerial;  ///< what "VID:PID" ports mean
  int default_baud = 115200;
  int stop_bits = 1;
  std::unique_ptr<ProtocolDecoder> (*make_decoder)(const DeviceSpec&) = nullptr;
  std::vector<SetupStep> (*setup)(const DeviceSpec&) = nullptr;
  bool fused_on_device = false;  ///< see mocap::fused_on_device
};

/// nullptr if unknown.
const ProtocolInfo* find_protocol(std::string_view name);
std::string protocol_names();

std::vector<SetupStep> witmotion_setup(const DeviceSpec& spec);
std::vector<SetupStep> xbus_setup(const DeviceSpec& spec);
std::vector<SetupStep> playstation_setup(const DeviceSpec& spec);
std::vector<SetupStep> joycon_setup(const DeviceSpec& spec);

}  // namespace mocap
