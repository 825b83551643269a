// Raw USB transport via libusb: finds a device by VID/PID/serial, claims the interface holding
// its first bulk or interrupt IN endpoint and streams it (Xsens MTi over USB).
#include <libusb-1.0/libusb.h>

#include "mocap/drivers/transport.hpp"

namespace mocap {
namespace {

class UsbTransport final : public ByteTransport {
 public:
  UsbTransport(libusb_context* ctx, libusb_device_handle* h, int iface, uint8_t ep_in,
               uint8_t ep_out, bool interrupt, std::string name)
      : ctx_(ctx),
        h_(h),
        iface_(iface),
        ep_in_(ep_in),
        ep_out_(ep_out),
        interrupt_(interrupt),
        name_(std::move(name)) {}
  ~UsbTransport() override {
    libusb_release_interface(h_, iface_);
    libusb_close(h_);
    libusb_exit(ctx_);
  }
  ReadResult read(std::span<uint8_t> buf, int timeout_ms, int /*wake_fd*/) override {
    ReadResult r;
    int n = 0;
    const unsigned t = static_cast<unsigned>(std::min(timeout_ms, 100));
    const int rc =
        interrupt_
            ? libusb_interrupt_transfer(h_, ep_in_, buf.data(), static_cast<int>(buf.size()), &n, t)
            : libusb_bulk_transfer(h_, ep_in_, buf.data(), static_cast<int>(buf.size()), &n, t);
    if (n > 0) {
      r.kind = ReadResult::kData;
      r.n = static_cast<std::size_t>(n);
    } else if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT && rc != LIBUSB_ERROR_INTERRUPTED) {
      r.kind = ReadResult::kVanished;
      r.reason = std::string("usb read: ") + libusb_error_name(rc);
    }
    return r;
  }
  bool write(std::span<const uint8_t> bytes, std::string& err) override {
    if (!ep_out_) return err = name_ + ": no OUT endpoint", false;
    int n = 0;
    const int rc = libusb_bulk_transfer(h_, ep_out_, const_cast<uint8_t*>(bytes.data()),
                                        static_cast<int>(bytes.size()), &n, 500);
    if (rc == 0 && n == static_cast<int>(bytes.size())) return true;
    err = name_ + ": usb write: " + libusb_error_name(rc);
    return false;
  }
  std::string describe() const override { return "usb " + name_; }

 private:
  libusb_context* ctx_;
  libusb_device_handle* h_;
  int iface_;
  uint8_t ep_in_, ep_out_;
  bool interrupt_;
  std::string name_;
};

}  // namespace

std::unique_ptr<ByteTransport> open_usb(const std::string& ids_text, std::string& err) {
  UsbIds ids;
  if (!parse_usb_ids(ids_text, ids, err)) return nullptr;
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) != 0) return err = "libusb initialisation failed", nullptr;
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(ctx, &list);
  libusb_device_handle* h = nullptr;
  libusb_device* dev = nullptr;
  for (ssize_t i = 0; i < count && !h; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != ids.vid ||
        d.idProduct != ids.pid)
      continue;
    libusb_device_handle* cand = nullptr;
    if (libusb_open(list[i], &cand) != 0) {
      err = "USB device " + ids_text +
            " cannot be opened (permissions? install config/udev/70-mocap.rules)";
      continue;
    }
    unsigned char serial[128] = {0};
    if (!ids.serial.empty() &&
        (d.iSerialNumber == 0 ||
         libusb_get_string_descriptor_ascii(cand, d.iSerialNumber, serial, sizeof serial) < 0 ||
         ids.serial != reinterpret_cast<char*>(serial))) {
      libusb_close(cand);
      continue;
    }
    h = cand;
    dev = list[i];
  }
  if (!h) {
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    if (err.empty()) err = "no USB device " + ids_text + " is connected";
    return nullptr;
  }
  libusb_config_descriptor* cfg = nullptr;
  int iface = -1;
  uint8_t ep_in = 0, ep_out = 0;
  bool interrupt = false;
  if (libusb_get_active_config_descriptor(dev, &cfg) == 0) {
    for (int i = 0; i < cfg->bNumInterfaces && iface < 0; ++i) {
      const auto& alt = cfg->interface[i].altsetting[0];
      for (int e = 0; e < alt.bNumEndpoints; ++e) {
        const auto& ep = alt.endpoint[e];
        const int type = ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
        if (type != LIBUSB_TRANSFER_TYPE_BULK && type != LIBUSB_TRANSFER_TYPE_INTERRUPT) continue;
        if (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) {
          if (!ep_in)
            ep_in = ep.bEndpointAddress, interrupt = type == LIBUSB_TRANSFER_TYPE_INTERRUPT;
        } else if (!ep_out) {
          ep_out = ep.bEndpointAddress;
        }
      }
      if (ep_in) iface = alt.bInterfaceNumber;
    }
    libusb_free_config_descriptor(cfg);
  }
  libusb_free_device_list(list, 1);
  libusb_set_auto_detach_kernel_driver(h, 1);
  if (iface < 0 || libusb_claim_interface(h, iface) != 0) {
    err = "USB device " + ids_text + ": no bulk/interrupt IN endpoint could be claimed";
    libusb_close(h);
    libusb_exit(ctx);
    return nullptr;
  }
  return std::make_unique<UsbTransport>(ctx, h, iface, ep_in, ep_out, interrupt, ids_text);
}

}  // namespace mocap
