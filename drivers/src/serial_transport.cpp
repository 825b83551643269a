// Serial transport: libserialport for real ports (found by path or USB VID/PID/serial), POSIX
// termios for paths libserialport refuses (pseudo-terminals, e.g. simulators and socat bridges).
#include <fcntl.h>
#include <libserialport.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

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

class SerialTransport final : public ByteTransport {
 public:
  SerialTransport(std::string name, sp_port* port, int fd)
      : name_(std::move(name)), port_(port), fd_(fd) {}
  ~SerialTransport() override {
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
    } else if (n < 0 && !port_ && (errno == EAGAIN || errno == EINTR)) {
      r.kind = ReadResult::kTimeout;
    } else {
      r.kind = ReadResult::kVanished;
      r.reason = n == 0 ? "end of file (device closed)"
                        : std::string("read: ") + (port_ ? sp_error() : std::strerror(errno));
    }
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

 private:
  std::string name_;
  sp_port* port_;
  int fd_;
};

std::unique_ptr<ByteTransport> open_termios(const SerialOptions& opt, std::string& err) {
  const int fd = ::open(opt.port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    err = opt.port + ": " + std::strerror(errno);
    return nullptr;
  }
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    err = opt.port + ": not a terminal: " + std::strerror(errno);
    ::close(fd);
    return nullptr;
  }
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
  return std::make_unique<SerialTransport>(opt.port, nullptr, fd);
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
  if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
    err = opt.port + ": cannot open: " + sp_error();
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
  return std::make_unique<SerialTransport>(opt.port, port, fd);
}

}  // namespace mocap
