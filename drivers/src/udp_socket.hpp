// Binding a UDP socket to "HOST:PORT" text for the drivers' UDP inputs: the generic UDP
// transport (udp_transport.cpp) and the SlimeVR server's socket (slimevr_device.cpp).
#pragma once

#include <string>

namespace mocap {

/// A close-on-exec UDP socket bound to host_port: IPv4 only if ipv4_only, SO_BROADCAST if
/// broadcast. Not SO_REUSEADDR (a second socket on the port would take the first one's unicast
/// datagrams, so a busy port is an error). -1 with "udp HOST:PORT: ..." in err on failure.
int bind_udp(const std::string& host_port, bool ipv4_only, bool broadcast, std::string& err);

}  // namespace mocap
