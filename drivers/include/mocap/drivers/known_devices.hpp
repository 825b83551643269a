// USB ids of devices the drivers support (or commonly carry a supported protocol), device
// enumeration over serial, HID and raw USB, and libusb hot-plug notification for known ids.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mocap {

struct KnownDevice {
  uint16_t vid, pid;
  const char* protocol;  ///< driver to use ("witmotion|line" when the chip is generic)
  const char* what;
  enum Kind { kSerial, kHid } kind;
};
/// The table (serial chips used by WitMotion/DIY boards, Xsens, Sony, Nintendo).
const std::vector<KnownDevice>& known_devices();

/// A connected device matching the table.
struct FoundDevice {
  const KnownDevice* known = nullptr;
  std::string transport;  ///< "serial", "hid", "usb"
  std::string path;       ///< /dev/ttyUSB0, hidraw path, or bus-address
  std::string serial;     ///< USB serial number (may be empty)
  std::string port;       ///< DeviceSpec.port to use
};
/// Enumerates serial ports (libserialport), HID devices (hidapi) and raw USB devices (libusb).
std::vector<FoundDevice> find_devices();

/// libusb hot-plug notification for the known ids (attach/detach), on its own event thread.
class UsbHotplug {
 public:
  using Callback = std::function<void(bool attached, uint16_t vid, uint16_t pid)>;
  /// Throws std::runtime_error if libusb has no hot-plug support on this system.
  explicit UsbHotplug(Callback cb);
  ~UsbHotplug();
  UsbHotplug(const UsbHotplug&) = delete;
  UsbHotplug& operator=(const UsbHotplug&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mocap
