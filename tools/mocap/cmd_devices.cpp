// mocap devices: lists connected serial, HID and USB devices that match a known driver, with the
// rig-config snippet to use each; --watch prints USB attach/detach events (libusb hot-plug).
#include <signal.h>

#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/drivers/known_devices.hpp"

namespace mocap::cmd {

namespace {

/// mocap devices' command line (declared in add_devices).
struct DevicesOptions {
  bool watch = false, known = false;
};

int run_devices(const DevicesOptions& o) {
  if (o.known) {
    for (const auto& k : known_devices())
      std::printf("%04x:%04x  %-5s  %-15s %s\n", k.vid, k.pid,
                  k.kind == KnownDevice::kHid ? "hid" : "serial", k.protocol, k.what);
    return 0;
  }
  const auto found = find_devices();
  if (found.empty())
    std::printf(
        "# no known serial, HID or USB device is connected (mocap devices --known lists the "
        "ids)\n");
  for (const auto& f : found) {
    std::printf("# %s: %s at %s%s%s\n", f.transport.c_str(), f.known->what, f.path.c_str(),
                f.serial.empty() ? "" : ", serial ", f.serial.c_str());
    const std::string proto = f.known->protocol;
    const auto bar = proto.find('|');
    std::printf("[[sensor]]\nname = \"%s_%zu\"\ndriver = \"%s\"%s\nport = \"%s\"\n",
                proto.substr(0, bar).c_str(), static_cast<std::size_t>(&f - found.data()),
                proto.substr(0, bar).c_str(),
                bar == std::string::npos
                    ? ""
                    : ("  # or \"" + proto.substr(bar + 1) + "\" for a DIY board").c_str(),
                f.port.c_str());
    if (proto == "xbus") std::printf("baud = 115200\n");
    std::printf("segment = \"pelvis\"  # choose the body segment\n\n");
  }
  if (!o.watch) return 0;
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGINT);
  sigaddset(&stop, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  try {
    UsbHotplug hp([](bool attached, uint16_t vid, uint16_t pid) {
      std::printf("%s %04x:%04x\n", attached ? "attached" : "detached", vid, pid);
      std::fflush(stdout);
    });
    std::printf("# watching USB (Ctrl-C to stop)\n");
    std::fflush(stdout);
    sigwaitinfo(&stop, nullptr);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap devices: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_devices(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<DevicesOptions>();
  CLI::App* c = cli::add_command(app, "devices",
                                 "list connected devices that a driver supports, with the rig "
                                 "config snippet of each");
  c->add_flag("--watch", o->watch,
              "after listing, print USB attach/detach of known devices until interrupted");
  c->add_flag("--known", o->known, "print the table of known USB ids");
  c->callback([o, &exit_code] { exit_code = run_devices(*o); });
}

}  // namespace mocap::cmd
