// Client side of a one-line request/reply exchange over a Unix stream socket (the daemon's
// control socket): used by mocapctl, the daemon's tests and mocap-viewer alike.
#pragma once

#include <string>
#include <string_view>

namespace mocap {

/// Connects to `path`, checks that the peer runs as our user (or root: another user may have
/// created the socket first), sends `request_line` (a newline added if missing) and returns the
/// reply's first line without its newline ("" if the peer closed without one). Throws
/// std::runtime_error naming `peer` and what failed: unreachable, a peer of another user, the
/// send, or no reply within timeout_ms.
std::string unix_line_call(const std::string& path, std::string_view request_line, int timeout_ms,
                           std::string_view peer);

}  // namespace mocap
