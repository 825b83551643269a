// libusb hot-plug notification for known device ids (see known_devices.hpp).
#include <libusb-1.0/libusb.h>

#include <atomic>
#include <stdexcept>
#include <thread>

#include "mocap/drivers/known_devices.hpp"

namespace mocap {

struct UsbHotplug::Impl {
  libusb_context* ctx = nullptr;
  libusb_hotplug_callback_handle handle = 0;
  Callback cb;
  std::atomic<bool> stop{false};
  std::thread thread;

  static int on_event(libusb_context*, libusb_device* dev, libusb_hotplug_event ev, void* user) {
    auto* self = static_cast<Impl*>(user);
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(dev, &d) != 0) return 0;
    for (const auto& k : known_devices())
      if (k.vid == d.idVendor && k.pid == d.idProduct)
        self->cb(ev == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED, d.idVendor, d.idProduct);
    return 0;
  }
};

UsbHotplug::UsbHotplug(Callback cb) : impl_(std::make_unique<Impl>()) {
  impl_->cb = std::move(cb);
  if (libusb_init(&impl_->ctx) != 0) throw std::runtime_error("libusb initialisation failed");
  if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
    libusb_exit(impl_->ctx);
    throw std::runtime_error("libusb has no hot-plug support here");
  }
  const int rc = libusb_hotplug_register_callback(
      impl_->ctx,
      static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                        LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
      LIBUSB_HOTPLUG_ENUMERATE, LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY,
      LIBUSB_HOTPLUG_MATCH_ANY, &Impl::on_event, impl_.get(), &impl_->handle);
  if (rc != LIBUSB_SUCCESS) {
    libusb_exit(impl_->ctx);
    throw std::runtime_error(std::string("libusb hot-plug registration failed: ") +
                             libusb_error_name(rc));
  }
  impl_->thread = std::thread([impl = impl_.get()] {
    while (!impl->stop) {
      timeval tv{0, 200'000};  // bounds the stop latency
      libusb_handle_events_timeout_completed(impl->ctx, &tv, nullptr);
    }
  });
}

UsbHotplug::~UsbHotplug() {
  impl_->stop = true;
  libusb_hotplug_deregister_callback(impl_->ctx, impl_->handle);  // wakes the event loop
  impl_->thread.join();
  libusb_exit(impl_->ctx);
}

}  // namespace mocap
