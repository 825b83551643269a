// Known USB ids and enumeration of connected devices over serial, HID and raw USB.
#include "mocap/drivers/known_devices.hpp"

#include <hidapi/hidapi.h>
#include <libserialport.h>
#include <libusb-1.0/libusb.h>

#include <cstdio>

namespace mocap {

const std::vector<KnownDevice>& known_devices() {
  static const std::vector<KnownDevice> kTable = {
      {0x1a86, 0x7523, "witmotion|line",
       "CH340 USB-serial (WitMotion WT901/HWT901B adapters, Arduino clones)", KnownDevice::kSerial},
      {0x10c4, 0xea60, "witmotion|line", "CP210x USB-serial (WitMotion adapters, ESP32 boards)",
       KnownDevice::kSerial},
      {0x0403, 0x6001, "witmotion|line", "FTDI FT232 USB-serial", KnownDevice::kSerial},
      {0x2341, 0x0043, "line", "Arduino Uno", KnownDevice::kSerial},
      {0x2341, 0x8036, "line", "Arduino Leonardo", KnownDevice::kSerial},
      {0x303a, 0x1001, "line", "Espressif ESP32-S3/C3 USB serial/JTAG", KnownDevice::kSerial},
      {0x2639, 0x0300, "xbus", "Xsens MTi (USB)", KnownDevice::kSerial},
      {0x2639, 0x0301, "xbus", "Xsens MTi (USB)", KnownDevice::kSerial},
      {0x2639, 0x0017, "xbus", "Xsens MTi USB converter", KnownDevice::kSerial},
      {0x2639, 0x0100, "xbus", "Xsens MTi (USB, 100-series)", KnownDevice::kSerial},
      {0x054c, 0x05c4, "ds4", "Sony DualShock 4 (v1)", KnownDevice::kHid},
      {0x054c, 0x09cc, "ds4", "Sony DualShock 4 (v2)", KnownDevice::kHid},
      {0x054c, 0x0ba0, "ds4", "Sony DualShock 4 USB wireless adapter", KnownDevice::kHid},
      {0x054c, 0x0ce6, "dualsense", "Sony DualSense", KnownDevice::kHid},
      {0x054c, 0x0df2, "dualsense", "Sony DualSense Edge", KnownDevice::kHid},
      {0x057e, 0x2006, "joycon", "Nintendo Joy-Con (L)", KnownDevice::kHid},
      {0x057e, 0x2007, "joycon", "Nintendo Joy-Con (R)", KnownDevice::kHid},
      {0x057e, 0x2009, "joycon", "Nintendo Switch Pro Controller", KnownDevice::kHid},
      {0x057e, 0x200e, "joycon", "Nintendo Joy-Con Charging Grip", KnownDevice::kHid},
      {0x1209, 0x7690, "slimevr_hid", "SlimeVR receiver dongle (Smol Slime trackers)",
       KnownDevice::kHid},
  };
  return kTable;
}

static const KnownDevice* lookup(int vid, int pid) {
  for (const auto& k : known_devices())
    if (k.vid == vid && k.pid == pid) return &k;
  return nullptr;
}

static std::string ids(uint16_t vid, uint16_t pid, const std::string& serial) {
  char b[32];
  std::snprintf(b, sizeof b, "%04x:%04x", vid, pid);
  return serial.empty() ? b : std::string(b) + ":" + serial;
}

std::vector<FoundDevice> find_devices() {
  std::vector<FoundDevice> out;
  sp_port** ports = nullptr;
  if (sp_list_ports(&ports) == SP_OK) {
    for (int i = 0; ports[i]; ++i) {
      int vid = 0, pid = 0;
      if (sp_get_port_transport(ports[i]) != SP_TRANSPORT_USB ||
          sp_get_port_usb_vid_pid(ports[i], &vid, &pid) != SP_OK)
        continue;
      const KnownDevice* k = lookup(vid, pid);
      if (!k) continue;
      const char* serial = sp_get_port_usb_serial(ports[i]);
      FoundDevice f{k, "serial", sp_get_port_name(ports[i]), serial ? serial : "", ""};
      f.port = f.serial.empty() ? f.path : "usb:" + ids(k->vid, k->pid, f.serial);
      out.push_back(f);
    }
    sp_free_port_list(ports);
  }
  if (hid_init() == 0) {
    hid_device_info* list = hid_enumerate(0, 0);
    for (auto* d = list; d; d = d->next) {
      const KnownDevice* k = lookup(d->vendor_id, d->product_id);
      if (!k || k->kind != KnownDevice::kHid) continue;
      std::string serial;
      for (const wchar_t* w = d->serial_number; w && *w; ++w)
        serial += *w < 128 ? static_cast<char>(*w) : '?';
      out.push_back({k, "hid", d->path, serial, "hid:" + ids(k->vid, k->pid, serial)});
    }
    hid_free_enumeration(list);
  }
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) == 0) {
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
      const KnownDevice* k = lookup(d.idVendor, d.idProduct);
      if (!k) continue;
      bool listed = false;  // already found as a serial port or HID device
      for (const auto& f : out)
        listed |= f.known == k;
      if (listed) continue;
      char where[32];
      std::snprintf(where, sizeof where, "bus %d device %d", libusb_get_bus_number(list[i]),
                    libusb_get_device_address(list[i]));
      out.push_back({k, "usb", where, "", "usb:" + ids(k->vid, k->pid, "")});
    }
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
  }
  return out;
}

}  // namespace mocap
