// Pseudo-terminal endpoint for simulated serial devices (see sim_encoder.hpp).
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/devsim/sim_encoder.hpp"

namespace mocap {

PtyEndpoint::PtyEndpoint(std::string link_path) : link_(std::move(link_path)) {
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0)
    throw std::runtime_error(std::string("cannot create a pseudo-terminal: ") +
                             std::strerror(errno));
  char name[128];
  if (ptsname_r(master_, name, sizeof name) != 0) throw std::runtime_error("ptsname failed");
  slave_ = name;
  // Raw mode: the line discipline must not echo, translate CR/LF or eat control bytes.
  termios tio{};
  tcgetattr(master_, &tio);
  cfmakeraw(&tio);
  tcsetattr(master_, TCSANOW, &tio);
  if (!link_.empty()) {
    const std::string tmp = link_ + ".tmp";
    ::unlink(tmp.c_str());
    if (::symlink(slave_.c_str(), tmp.c_str()) != 0 || ::rename(tmp.c_str(), link_.c_str()) != 0)
      throw std::runtime_error("cannot create link " + link_ + ": " + std::strerror(errno));
  }
}

PtyEndpoint::~PtyEndpoint() {
  if (!link_.empty()) ::unlink(link_.c_str());
  if (master_ >= 0) ::close(master_);
}

bool PtyEndpoint::write(std::span<const uint8_t> bytes) {
  std::size_t off = 0;
  while (off < bytes.size()) {
    const ssize_t n = ::write(master_, bytes.data() + off, bytes.size() - off);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    off += static_cast<std::size_t>(n);
  }
  return true;
}

std::size_t PtyEndpoint::read(std::span<uint8_t> buf, int timeout_ms) {
  pollfd p{master_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0 || !(p.revents & POLLIN)) return 0;
  const ssize_t n = ::read(master_, buf.data(), buf.size());
  return n > 0 ? static_cast<std::size_t>(n) : 0;  // EIO: no slave open
}

}  // namespace mocap
