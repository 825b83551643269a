// mocap devices: lists connected serial, HID and USB devices that match a known driver, with the
// rig-config snippet to use each; --watch prints USB attach/detach events (libusb hot-plug).
#include <signal.h>

#include <cstdio>

#include "commands.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/drivers/known_devices.hpp"

namespace mocap::cmd {

int run_devices(int argc, char** argv) {
  CliArgs args;
  args.flag("watch", "after listing, print USB attach/detach of known devices until interrupted")
      .flag("known", "print the table of known USB ids")
      .flag("help", "show this help");
  if (!args.parse(argc, argv)) {
    std::fprintf(stderr, "mocap devices: %s\n%s", args.error().c_str(), args.help().c_str());
    return 2;
  }
  if (args.has("help")) {
    std::printf("usage: mocap devices [--watch] [--known]\n%s", args.help().c_str());
    return 0;
  }
  if (args.has("known")) {
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
  if (!args.has("watch")) return 0;
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

}  // namespace mocap::cmd
