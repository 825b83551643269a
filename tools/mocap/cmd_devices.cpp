// mocap devices: lists connected serial, HID and USB devices that match a known driver, with the
// rig-config snippet to use each, and the SlimeVR trackers heard saying hello on UDP 6969;
// --watch prints USB attach/detach events (libusb hot-plug).
#include <signal.h>

#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/drivers/known_devices.hpp"
#include "mocap/drivers/slimevr.hpp"
#include "mocap/drivers/slimevr_listen.hpp"

namespace mocap::cmd {

namespace {

/// The SlimeVR boards heard saying hello (handshake broadcasts of trackers not yet connected),
/// each with the rig snippet of its main IMU.
void list_slimevr(int port, double seconds) {
  std::string err;
  const std::string addr = "0.0.0.0:" + std::to_string(port);
  const auto hellos = listen_slimevr_hellos(addr, static_cast<int>(seconds * 1000), err);
  if (!err.empty()) {
    std::printf(
        "# SlimeVR: cannot listen on udp %s (%s); if mocapd runs there, `mocapctl "
        "status` shows its trackers\n",
        addr.c_str(), err.c_str());
    return;
  }
  if (hellos.empty())
    std::printf("# SlimeVR: no tracker said hello on udp %s in %.1f s\n", addr.c_str(), seconds);
  for (const auto& h : hellos) {
    const auto named = [](const char* name) { return name ? name : "?"; };
    std::printf(
        "# slimevr: tracker %s at %s (board %u %s, IMU %u %s, MCU %u %s, firmware \"%s\", "
        "protocol %u)\n",
        h.mac.c_str(), h.ip.c_str(), h.board, named(slimevr::board_name(h.board)), h.imu,
        named(slimevr::imu_name(h.imu)), h.mcu, named(slimevr::mcu_name(h.mcu)), h.firmware.c_str(),
        h.protocol_version);
    std::printf(
        "[[sensor]]\nname = \"slime_%s\"\ndriver = \"slimevr\"\nport = \"udp:%s\"\n"
        "segment = \"pelvis\"  # choose the body segment\n"
        "options = { mac = \"%s\", tracker = 0 }  # tracker = 1: the extension IMU\n\n",
        h.mac.substr(12, 2).append(h.mac.substr(15, 2)).c_str(), addr.c_str(), h.mac.c_str());
  }
}

/// mocap devices' command line (declared in add_devices).
struct DevicesOptions {
  bool watch = false, known = false;
  double slimevr_listen_s = 1.5;
  int slimevr_port = 6969;
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
  if (o.slimevr_listen_s > 0) list_slimevr(o.slimevr_port, o.slimevr_listen_s);
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
  c->add_option("--slimevr-listen", o->slimevr_listen_s,
                "seconds to listen for SlimeVR trackers' hello (0 = no)")
      ->check(CLI::Range(0.0, 600.0));
  c->add_option("--slimevr-port", o->slimevr_port, "UDP port of the SlimeVR trackers' hello")
      ->check(CLI::Range(1, 65535));
  c->callback([o, &exit_code] { exit_code = run_devices(*o); });
}

}  // namespace mocap::cmd
