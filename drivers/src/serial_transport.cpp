// Serial transport: libserialport for real ports (found by path or USB VID/PID/serial), POSIX
// termios for paths libserialport refuses (pseudo-terminals, e.g. simulators and socat bridges).
#include <dirent.h>
#include <fcntl.h>
#include <libserialport.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "fd_wait.hpp"
#include "mocap/drivers/transport.hpp"

namespace mocap {
namespace {

std::string sp_error() {
  char* msg = sp_last_error_message();
  std::string s = msg ? msg : "unknown error";
  sp_free_error_message(msg);
  return s;
}

speed_t termios_speed(int baud) {
  switch (baud) {
    case 4800:
      return B4800;
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    case 2000000:
      return B2000000;
    case 4000000:
      return B4000000;
    default:
      return B0;
  }
}

/// What to tell the user when opening a port fails with EBUSY.
std::string busy_message(const std::string& port) {
  return port +
         ": busy: another process holds this port exclusively (another mocapd, a serial "
         "terminal, ModemManager, ...; `fuser -v " +
         port + "` names it)";
}

/// Other processes that have the same character device open (by /proc/PID/fd links), as
/// "PID (name)"; at most 4. Processes of other users are not visible without privileges.
std::string other_openers(const std::string& port) {
  char real[PATH_MAX];
  if (!::realpath(port.c_str(), real)) return {};
  const std::string target = real;
  const std::string self = std::to_string(::getpid());
  std::string found;
  int count = 0;
  DIR* proc = ::opendir("/proc");
  if (!proc) return {};
  while (dirent* pe = ::readdir(proc)) {
    if (pe->d_name[0] < '1' || pe->d_name[0] > '9' || self == pe->d_name) continue;
    const std::string fd_dir = std::string("/proc/") + pe->d_name + "/fd";
    DIR* fds = ::opendir(fd_dir.c_str());
    if (!fds) continue;
    bool holds = false;
    while (dirent* fe = ::readdir(fds)) {
      if (fe->d_name[0] == '.') continue;
      char link[PATH_MAX];
      const ssize_t n = ::readlink((fd_dir + "/" + fe->d_name).c_str(), link, sizeof link - 1);
      if (n > 0 && target == std::string_view(link, static_cast<std::size_t>(n))) {
        holds = true;
        break;
      }
    }
    ::closedir(fds);
    if (!holds) continue;
    std::string comm;
    std::ifstream(std::string("/proc/") + pe->d_name + "/comm") >> comm;
    if (++count <= 4)
      found += (found.empty() ? "" : ", ") + std::string(pe->d_name) + " (" + comm + ")";
  }
  ::closedir(proc);
  return found;
}

/// Takes the port for this process: TIOCEXCL (further open()s by non-root processes fail with
/// EBUSY) and an exclusive flock (as pyserial's exclusive mode and lockdev-style tools do).
/// False + err when another process already holds the lock.
bool take_exclusive(int fd, const std::string& port, std::string& err) {
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK)
    return err = busy_message(port), false;
  ::ioctl(fd, TIOCEXCL);  // best effort (not every tty supports it)
  return true;
}

class SerialTransport final : public ByteTransport {
 public:
  /// others: processes that had the port open before it was configured (other_openers()).
  SerialTransport(std::string name, sp_port* port, int fd, const std::string& others)
      : name_(std::move(name)), port_(port), fd_(fd) {
    if (!others.empty())
      warning_ = name_ + " is also open in process " + others +
                 ": a second reader takes bytes from this one (close it)";
  }
  ~SerialTransport() override {
    // A pty's tty outlives this close while its master is open: leave it non-exclusive.
    if (fd_ >= 0) ::ioctl(fd_, TIOCNXCL);
    if (port_) {
      sp_close(port_);
      sp_free_port(port_);
    } else if (fd_ >= 0) {
      ::close(fd_);
    }
  }

  ReadResult read(std::span<uint8_t> buf, int timeout_ms, int wake_fd) override {
    ReadResult r = wait_fd(fd_, wake_fd, timeout_ms);
    if (r.kind != ReadResult::kData) return r;
    const ssize_t n = port_
                          ? static_cast<ssize_t>(sp_nonblocking_read(port_, buf.data(), buf.size()))
                          : ::read(fd_, buf.data(), buf.size());
    if (n > 0) {
      r.n = static_cast<std::size_t>(n);
      empty_reads_ = 0;
      return r;
    }
    // libserialport returns 0 on EAGAIN itself; its failures keep errno in sp_last_error_code.
    const int e = port_ ? sp_last_error_code() : errno;
    if (n < 0 && !port_ && (e == EAGAIN || e == EINTR)) return r.kind = ReadResult::kTimeout, r;
    if (n < 0 && e == EIO) {
      r.kind = ReadResult::kVanished;
      r.reason = "hang-up (EIO: device unplugged or its other end closed)";
      return r;
    }
    if (n < 0) {
      r.kind = ReadResult::kVanished;
      r.reason = std::string("read: ") + (port_ ? sp_error() : std::strerror(e));
      return r;
    }
    // 0 bytes after poll said readable: a hang-up only if the port says so (POLLHUP/POLLERR);
    // otherwise another reader took the bytes first, or the wake-up was spurious: no data.
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) >= 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) {
      r.kind = ReadResult::kVanished;
      r.reason = (p.revents & POLLHUP) ? "hang-up (device unplugged or closed)" : "device error";
      return r;
    }
    if (++empty_reads_ >= kMaxEmptyReads) {  // readable forever without data: not a live port
      empty_reads_ = 0;
      r.kind = ReadResult::kVanished;
      r.reason = "port keeps signalling data but none arrives";
      return r;
    }
    r.kind = ReadResult::kTimeout;
    return r;
  }

  bool write(std::span<const uint8_t> bytes, std::string& err) override {
    if (port_) {
      const int n = sp_blocking_write(port_, bytes.data(), bytes.size(), 500);
      if (n == static_cast<int>(bytes.size())) return true;
      err = name_ + ": write failed: " + (n < 0 ? sp_error() : "timeout");
      return false;
    }
    std::size_t off = 0;
    while (off < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + off, bytes.size() - off);
      if (n < 0 && errno == EAGAIN) {
        pollfd p{fd_, POLLOUT, 0};
        if (::poll(&p, 1, 500) <= 0) return err = name_ + ": write timeout", false;
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return err = name_ + ": write: " + std::strerror(errno), false;
      off += static_cast<std::size_t>(n);
    }
    return true;
  }

  bool set_baud(int baud, std::string& err) override {
    if (port_) {
      if (sp_set_baudrate(port_, baud) == SP_OK) return true;
      err = name_ + ": cannot set baud " + std::to_string(baud) + ": " + sp_error();
      return false;
    }
    termios tio{};
    const speed_t sp = termios_speed(baud);
    if (sp == B0 || tcgetattr(fd_, &tio) != 0) return err = name_ + ": unsupported baud", false;
    cfsetispeed(&tio, sp);
    cfsetospeed(&tio, sp);
    if (tcsetattr(fd_, TCSANOW, &tio) != 0) return err = name_ + ": " + std::strerror(errno), false;
    return true;
  }

  std::string describe() const override {
    return name_ + (port_ ? " (libserialport)" : " (termios)");
  }
  std::string warning() const override { return warning_; }

 private:
  static constexpr int kMaxEmptyReads = 10000;
  std::string name_;
  sp_port* port_;
  int fd_;
  int empty_reads_ = 0;
  std::string warning_;
};

std::unique_ptr<ByteTransport> open_termios(const SerialOptions& opt, std::string& err) {
  const int fd = ::open(opt.port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    err = errno == EBUSY ? busy_message(opt.port) : opt.port + ": " + std::strerror(errno);
    return nullptr;
  }
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    err = opt.port + ": not a terminal: " + std::strerror(errno);
    ::close(fd);
    return nullptr;
  }
  if (!take_exclusive(fd, opt.port, err)) {
    ::close(fd);
    return nullptr;
  }
  // Before configuring: a blocking reader elsewhere may give up once VMIN becomes 0.
  const std::string others = other_openers(opt.port);
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~CRTSCTS;
  if (opt.stop_bits == 2)
    tio.c_cflag |= CSTOPB;
  else
    tio.c_cflag &= ~CSTOPB;
  const speed_t sp = termios_speed(opt.baud);
  if (sp != B0) {
    cfsetispeed(&tio, sp);
    cfsetospeed(&tio, sp);
  }
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    err = opt.port + ": cannot configure: " + std::strerror(errno);
    ::close(fd);
    return nullptr;
  }
  return std::make_unique<SerialTransport>(opt.port, nullptr, fd, others);
}

/// Finds the port name of a USB-serial adapter by ids; empty + err if none matches.
std::string find_usb_serial(const std::string& ids_text, std::string& err) {
  UsbIds ids;
  if (!parse_usb_ids(ids_text, ids, err)) return {};
  sp_port** list = nullptr;
  if (sp_list_ports(&list) != SP_OK) {
    err = "cannot list serial ports: " + sp_error();
    return {};
  }
  std::string found;
  for (int i = 0; list[i] && found.empty(); ++i) {
    if (sp_get_port_transport(list[i]) != SP_TRANSPORT_USB) continue;
    int vid = 0, pid = 0;
    if (sp_get_port_usb_vid_pid(list[i], &vid, &pid) != SP_OK) continue;
    if (vid != ids.vid || pid != ids.pid) continue;
    const char* serial = sp_get_port_usb_serial(list[i]);
    if (!ids.serial.empty() && (!serial || ids.serial != serial)) continue;
    found = sp_get_port_name(list[i]);
  }
  sp_free_port_list(list);
  if (found.empty()) err = "no USB serial port with ids " + ids_text + " is connected";
  return found;
}

}  // namespace

std::unique_ptr<ByteTransport> open_serial(const SerialOptions& opt_in, std::string& err) {
  SerialOptions opt = opt_in;
  if (opt.port.rfind("usb:", 0) == 0) {
    opt.port = find_usb_serial(opt.port.substr(4), err);
    if (opt.port.empty()) return nullptr;
  }
  sp_port* port = nullptr;
  if (sp_get_port_by_name(opt.port.c_str(), &port) != SP_OK) {
    // libserialport refuses pseudo-terminals (SP_ERR_ARG): use termios with the same interface.
    if (::access(opt.port.c_str(), F_OK) != 0) {
      err = opt.port + ": " + std::strerror(errno);
      return nullptr;
    }
    return open_termios(opt, err);
  }
  const std::string others = other_openers(opt.port);
  if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
    err = sp_last_error_code() == EBUSY ? busy_message(opt.port)
                                        : opt.port + ": cannot open: " + sp_error();
    sp_free_port(port);
    return nullptr;
  }
  if (sp_set_baudrate(port, opt.baud) != SP_OK || sp_set_bits(port, 8) != SP_OK ||
      sp_set_parity(port, SP_PARITY_NONE) != SP_OK ||
      sp_set_stopbits(port, opt.stop_bits) != SP_OK ||
      sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE) != SP_OK) {
    err = opt.port + ": cannot configure " + std::to_string(opt.baud) + " baud: " + sp_error();
    sp_close(port);
    sp_free_port(port);
    return nullptr;
  }
  int fd = -1;
  sp_get_port_handle(port, &fd);
  if (fd >= 0 && !take_exclusive(fd, opt.port, err)) {
    sp_close(port);
    sp_free_port(port);
    return nullptr;
  }
  return std::make_unique<SerialTransport>(opt.port, port, fd, others);
}

}  // namespace mocap
