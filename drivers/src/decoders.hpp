// Factories of the per-protocol decoders (internal; the public entry is make_decoder()).
#pragma once

#include <memory>

#include "decoder_common.hpp"

namespace mocap {

std::unique_ptr<ProtocolDecoder> make_line_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_witmotion_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_xbus_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_playstation_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_joycon_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_slimevr_decoder(const DeviceSpec& spec);
std::unique_ptr<ProtocolDecoder> make_slimevr_hid_decoder(const DeviceSpec& spec);
/// SlimeVR trackers: one UDP socket and thread for every tracker of the spec's mapping.
std::unique_ptr<Device> make_slimevr_device(const DeviceSpec& spec, Logger log);

}  // namespace mocap
