// USB HID transport via hidapi (hidraw backend): input reports with a timeout, feature reports,
// output reports. Each read returns one report (byte 0 = report id).
#include <hidapi/hidapi.h>

#include <algorithm>
#include <cwchar>

#include "mocap/drivers/transport.hpp"

namespace mocap {
namespace {

std::string narrow(const wchar_t* w) {
  std::string s;
  for (; w && *w; ++w)
    s += *w < 128 ? static_cast<char>(*w) : '?';
  return s;
}

class HidTransport final : public ByteTransport {
 public:
  HidTransport(hid_device* dev, std::string name) : dev_(dev), name_(std::move(name)) {}
  ~HidTransport() override { hid_close(dev_); }

  ReadResult read(std::span<uint8_t> buf, int timeout_ms, int /*wake_fd*/) override {
    ReadResult r;
    const int n = hid_read_timeout(dev_, buf.data(), buf.size(), std::min(timeout_ms, 100));
    if (n < 0) {
      r.kind = ReadResult::kVanished;
      r.reason = "hid read: " + narrow(hid_error(dev_));
    } else if (n > 0) {
      r.kind = ReadResult::kData;
      r.n = static_cast<std::size_t>(n);
    }
    return r;
  }
  bool write(std::span<const uint8_t> bytes, std::string& err) override {
    if (hid_write(dev_, bytes.data(), bytes.size()) >= 0) return true;
    err = name_ + ": hid write: " + narrow(hid_error(dev_));
    return false;
  }
  int get_feature(std::span<uint8_t> buf, std::string& err) override {
    const int n = hid_get_feature_report(dev_, buf.data(), buf.size());
    if (n < 0) err = name_ + ": feature report: " + narrow(hid_error(dev_));
    return n;
  }
  bool set_feature(std::span<const uint8_t> bytes, std::string& err) override {
    if (hid_send_feature_report(dev_, bytes.data(), bytes.size()) >= 0) return true;
    err = name_ + ": set feature report: " + narrow(hid_error(dev_));
    return false;
  }
  bool record_framed() const override { return true; }
  std::string describe() const override { return "hid " + name_; }

 private:
  hid_device* dev_;
  std::string name_;
};

}  // namespace

std::unique_ptr<ByteTransport> open_hid(const std::string& ids_text, std::string& err) {
  UsbIds ids;
  if (!parse_usb_ids(ids_text, ids, err)) return nullptr;
  if (hid_init() != 0) {
    err = "hidapi initialisation failed";
    return nullptr;
  }
  hid_device_info* list = hid_enumerate(ids.vid, ids.pid);
  std::string path;
  for (auto* d = list; d && path.empty(); d = d->next)
    if (ids.serial.empty() || narrow(d->serial_number) == ids.serial) path = d->path;
  hid_free_enumeration(list);
  if (path.empty()) {
    err = "no HID device " + ids_text + " is connected";
    return nullptr;
  }
  hid_device* dev = hid_open_path(path.c_str());
  if (!dev) {
    err = "HID device " + ids_text + " at " + path +
          " cannot be opened (permissions? install config/udev/70-mocap.rules)";
    return nullptr;
  }
  return std::make_unique<HidTransport>(dev, ids_text + " " + path);
}

}  // namespace mocap
