// make_decoder() / make_device(): the protocol table and the choice of transport from the port.
#include <cstdio>
#include <stdexcept>

#include "mocap/drivers/device.hpp"
#include "mocap/drivers/transport.hpp"
#include "protocols.hpp"
#include "stream_device.hpp"

namespace mocap {

namespace {
const ProtocolInfo kProtocols[] = {
    {"line", ProtocolInfo::kSerial, 115200, 1, make_line_decoder, nullptr},
    {"witmotion", ProtocolInfo::kSerial, 9600, 1, make_witmotion_decoder, witmotion_setup},
    {"xbus", ProtocolInfo::kSerial, 115200, 2, make_xbus_decoder, xbus_setup},
    {"ds4", ProtocolInfo::kHid, 0, 1, make_playstation_decoder, playstation_setup},
    {"dualsense", ProtocolInfo::kHid, 0, 1, make_playstation_decoder, playstation_setup},
    {"joycon", ProtocolInfo::kHid, 0, 1, make_joycon_decoder, joycon_setup},
    {"slimevr", ProtocolInfo::kUdp, 0, 1, make_slimevr_decoder, nullptr, true},
    {"slimevr_hid", ProtocolInfo::kHid, 0, 1, make_slimevr_hid_decoder, nullptr},
};
}  // namespace

const ProtocolInfo* find_protocol(std::string_view name) {
  for (const auto& p : kProtocols)
    if (p.name == name) return &p;
  return nullptr;
}

bool fused_on_device(std::string_view protocol) {
  const ProtocolInfo* p = find_protocol(protocol);
  return p && p->fused_on_device;
}

std::string protocol_names() {
  std::string s;
  for (const auto& p : kProtocols)
    s += (s.empty() ? "" : ", ") + std::string(p.name);
  return s;
}

static const ProtocolInfo& require_protocol(const DeviceSpec& spec) {
  const ProtocolInfo* p = find_protocol(spec.protocol);
  if (!p)
    throw std::invalid_argument("device " + spec.name + ": unknown protocol \"" + spec.protocol +
                                "\" (known: " + protocol_names() + ")");
  return *p;
}

std::unique_ptr<StreamDecoder> make_decoder(const DeviceSpec& spec) {
  return require_protocol(spec).make_decoder(spec);
}

std::string serial_link_warning(const DeviceSpec& spec) {
  const ProtocolInfo* info = find_protocol(spec.protocol);
  if (!info || info->transport != ProtocolInfo::kSerial) return {};
  const std::string& port = spec.port;
  if (port.rfind("udp:", 0) == 0 || port.rfind("hid:", 0) == 0) return {};
  double bytes = 0, rate = spec.rate_hz;
  if (spec.protocol == "witmotion") {
    bytes = 6 * 11;  // time, acc, gyro, angle, mag, quaternion packets of 11 bytes (as set up)
  } else if (spec.protocol == "xbus") {
    if (port.rfind("usb:", 0) == 0) return {};  // may be raw USB (no baud)
    // MTData2: FA FF 36 LEN + CS, and id+size+data for the counter (2), SampleTimeFine (4),
    // quaternion (16), acceleration, rate of turn and magnetic field (12 each).
    bytes = 5 + (3 + 2) + (3 + 4) + (3 + 16) + 3 * (3 + 12);
    if (rate <= 0) rate = 100;  // what the driver asks for
  } else {
    return {};  // line protocol: lines of any length at the device's own rate
  }
  if (rate <= 0) return {};
  const int baud = spec.baud > 0 ? spec.baud : info->default_baud;
  const double stop_bits = option_double(spec, "stop_bits", info->stop_bits);
  const double bits_per_byte = 1 + 8 + stop_bits;
  const double need = rate * bytes * bits_per_byte;
  if (need <= baud) return {};
  char msg[400];
  std::snprintf(msg, sizeof msg,
                "%s at %g Hz needs %.0f bit/s (%g bytes a sample x %g bits a byte) but %d baud "
                "carries %d: at most %d samples/s arrive; raise baud (and the device's own, "
                "docs/devices.md) or lower rate_hz",
                spec.protocol.c_str(), rate, need, bytes, bits_per_byte, baud, baud,
                static_cast<int>(baud / (bytes * bits_per_byte)));
  return msg;
}

std::unique_ptr<Device> make_device(const DeviceSpec& spec, Logger log) {
  const ProtocolInfo& info = require_protocol(spec);
  if (info.transport == ProtocolInfo::kUdp) return make_slimevr_device(spec, std::move(log));
  auto decoder = info.make_decoder(spec);
  if (spec.port.empty()) throw std::invalid_argument("device " + spec.name + ": no port given");
  TransportOpener opener;
  const std::string& port = spec.port;
  if (port.rfind("udp:", 0) == 0) {
    const std::string addr = port.substr(4);
    opener = [addr](std::string& err) { return open_udp(addr, err); };
  } else if (port.rfind("hid:", 0) == 0) {
    const std::string ids = port.substr(4);
    UsbIds parsed;
    std::string err;
    if (!parse_usb_ids(ids, parsed, err))
      throw std::invalid_argument("device " + spec.name + ": " + err);
    opener = [ids](std::string& e) { return open_hid(ids, e); };
  } else {
    if (info.transport == ProtocolInfo::kHid && port.rfind("usb:", 0) != 0)
      throw std::invalid_argument("device " + spec.name + ": protocol " + spec.protocol +
                                  " is USB HID; give port as hid:VID:PID[:SERIAL]");
    SerialOptions opt;
    opt.port = port;
    opt.baud = spec.baud > 0 ? spec.baud : info.default_baud;
    opt.stop_bits = static_cast<int>(option_double(spec, "stop_bits", info.stop_bits));
    if (opt.stop_bits != 1 && opt.stop_bits != 2)
      throw std::invalid_argument("device " + spec.name + ": stop_bits must be 1 or 2");
    if (port.rfind("usb:", 0) == 0) {
      UsbIds parsed;
      std::string err;
      if (!parse_usb_ids(port.substr(4), parsed, err))
        throw std::invalid_argument("device " + spec.name + ": " + err);
      // A USB-serial adapter if one matches, else the raw USB device (vendor endpoints).
      opener = [opt](std::string& e) {
        auto t = open_serial(opt, e);
        if (t) return t;
        std::string e2;
        t = open_usb(opt.port.substr(4), e2);
        if (!t) e += "; raw USB: " + e2;
        return t;
      };
    } else {
      opener = [opt](std::string& e) { return open_serial(opt, e); };
    }
  }
  std::vector<SetupStep> setup = info.setup ? info.setup(spec) : std::vector<SetupStep>{};
  return std::make_unique<StreamDevice>(spec, std::move(log), std::move(opener), std::move(decoder),
                                        std::move(setup));
}

}  // namespace mocap

namespace mocap {

std::unique_ptr<Device> make_device_with_transport(
    const DeviceSpec& spec, Logger log,
    std::function<std::unique_ptr<ByteTransport>(std::string& err)> open) {
  const ProtocolInfo& info = require_protocol(spec);
  std::vector<SetupStep> setup = info.setup ? info.setup(spec) : std::vector<SetupStep>{};
  return std::make_unique<StreamDevice>(spec, std::move(log), std::move(open),
                                        info.make_decoder(spec), std::move(setup));
}

}  // namespace mocap
