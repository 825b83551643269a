// Byte transports a Device reads from: serial (libserialport, or POSIX termios for paths it
// refuses such as pseudo-terminals), UDP datagrams, USB HID (hidapi) and raw USB bulk/interrupt
// endpoints (libusb). Reads block until data, a hang-up, a wake-up or a timeout: no polling.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mocap {

struct ReadResult {
  enum Kind { kData, kTimeout, kWoken, kVanished } kind = kTimeout;
  std::size_t n = 0;   ///< bytes read (kData)
  std::string reason;  ///< why the transport vanished (kVanished)
};

class ByteTransport {
 public:
  virtual ~ByteTransport() = default;
  /// Blocks up to timeout_ms for data; returns early with kWoken when wake_fd becomes readable.
  virtual ReadResult read(std::span<uint8_t> buf, int timeout_ms, int wake_fd) = 0;
  /// Writes all bytes (configuration commands, HID output reports). False + err on failure.
  virtual bool write(std::span<const uint8_t> bytes, std::string& err) = 0;
  /// HID feature report (buf[0] = report id on input); returns its length, or -1 if unsupported.
  virtual int get_feature(std::span<uint8_t> /*buf*/, std::string& err) {
    err = "feature reports are not supported by this transport";
    return -1;
  }
  /// Sends a HID feature report (bytes[0] = report id). False + err if unsupported/failed.
  virtual bool set_feature(std::span<const uint8_t> /*bytes*/, std::string& err) {
    err = "feature reports are not supported by this transport";
    return false;
  }
  virtual bool set_baud(int /*baud*/, std::string& /*err*/) { return true; }
  /// True when each read returns one whole record (UDP datagram, HID report, USB transfer).
  virtual bool record_framed() const { return false; }
  virtual std::string describe() const = 0;
  /// Something the user should know about the open transport (e.g. another process has the
  /// same serial port open and takes bytes from this reader); empty when all is well.
  virtual std::string warning() const { return {}; }
};

struct SerialOptions {
  std::string port;  ///< path, or "usb:VID:PID[:SERIAL]" (hex ids) to find a USB-serial adapter
  int baud = 115200;
  int stop_bits = 1;  ///< 2 for Xsens
};
/// Opens a serial port. Returns nullptr and fills err (naming the port) on failure. The port is
/// taken exclusively (TIOCEXCL and flock): a port another process holds that way fails with a
/// message saying so; other processes that merely have it open are named in warning().
std::unique_ptr<ByteTransport> open_serial(const SerialOptions& opt, std::string& err);

/// Binds a UDP socket to "HOST:PORT" (HOST may be 0.0.0.0 or a name). nullptr + err on failure.
std::unique_ptr<ByteTransport> open_udp(const std::string& host_port, std::string& err);
/// Splits "HOST:PORT" (HOST may be empty or [bracketed]); false with the reason in err.
bool split_host_port(const std::string& hp, std::string& host, std::string& port, std::string& err);

/// Opens a HID device by ids ("VID:PID[:SERIAL]" hex). nullptr + err on failure.
std::unique_ptr<ByteTransport> open_hid(const std::string& ids, std::string& err);

/// Opens a raw USB device by ids ("VID:PID[:SERIAL]" hex) and streams its first bulk or
/// interrupt IN endpoint (writes go to the first OUT endpoint). nullptr + err on failure.
std::unique_ptr<ByteTransport> open_usb(const std::string& ids, std::string& err);

/// USB ids parsed from "VID:PID[:SERIAL]" (hex VID/PID). Returns false and fills err if malformed.
struct UsbIds {
  uint16_t vid = 0, pid = 0;
  std::string serial;
};
bool parse_usb_ids(const std::string& text, UsbIds& ids, std::string& err);

}  // namespace mocap
