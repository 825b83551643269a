// The simulated-device side of every protocol: an encoder turns truth samples into the exact
// bytes the real device sends (counters, timestamps, checksums) and answers host commands the
// way the device does. Used by `mocap simulate`, the driver tests and the virtual performer.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"

namespace mocap {

struct EncoderOptions {
  double rate_hz = 100;  ///< output rate the device starts with
  /// Protocol-specific: witmotion "quat_order" (wxyz|xyzw), line "units", ...
  std::map<std::string, std::string> options;
};

class ProtocolEncoder {
 public:
  virtual ~ProtocolEncoder() = default;
  /// Appends the device's bytes for one truth sample: device frame, SI units, q_device_sensor
  /// as the device's orientation output, t_device_ns = device clock. Record-framed protocols
  /// (HID) append whole reports of report_size() bytes (possibly none: Joy-Con sends three
  /// samples per report).
  virtual void encode(const ImuSample& truth, std::vector<uint8_t>& out) = 0;
  /// Bytes the host wrote; appends the device's replies and applies the commands.
  virtual void handle_host_bytes(std::span<const uint8_t> /*in*/, std::vector<uint8_t>& /*reply*/) {
  }
  /// For one-way links (UDP): the reports a host would otherwise request at open, such as the
  /// calibration (appended as whole reports). Default: none.
  virtual void unsolicited(std::vector<uint8_t>& /*out*/) {}
  /// HID feature report `id` (calibration); false if the device has none.
  virtual bool feature_report(uint8_t /*id*/, std::vector<uint8_t>& /*out*/) { return false; }
  /// False while the device is not streaming (e.g. Xbus configuration mode).
  virtual bool streaming() const { return true; }
  /// Current output rate (host commands may change it).
  virtual double rate_hz() const = 0;
  /// 0 for byte streams; the report size for HID protocols.
  virtual std::size_t report_size() const { return 0; }
};

/// Throws std::invalid_argument for an unknown protocol or bad option.
std::unique_ptr<ProtocolEncoder> make_encoder(std::string_view protocol, const EncoderOptions& opt);

/// A pseudo-terminal standing in for a serial port: the device writes to the master, the driver
/// opens the slave path. An optional stable symlink points at the slave (so a device that
/// "returns" on a new pty is found at the same path).
class PtyEndpoint {
 public:
  explicit PtyEndpoint(std::string link_path = "");  ///< throws std::runtime_error
  ~PtyEndpoint();
  PtyEndpoint(const PtyEndpoint&) = delete;
  PtyEndpoint& operator=(const PtyEndpoint&) = delete;
  /// The path the driver opens (the link if one was asked for, else /dev/pts/N).
  const std::string& path() const { return link_.empty() ? slave_ : link_; }
  const std::string& slave_path() const { return slave_; }
  /// Non-blocking write; returns false if not everything fit (no reader draining the pty).
  bool write(std::span<const uint8_t> bytes);
  /// Host-to-device bytes, waiting up to timeout_ms; 0 when none.
  std::size_t read(std::span<uint8_t> buf, int timeout_ms);
  int fd() const { return master_; }

 private:
  int master_ = -1;
  std::string slave_, link_;
};

/// Sends datagrams to HOST:PORT (a wireless sensor). Throws std::runtime_error on bad address.
class UdpSender {
 public:
  explicit UdpSender(const std::string& host_port);
  ~UdpSender();
  UdpSender(const UdpSender&) = delete;
  UdpSender& operator=(const UdpSender&) = delete;
  bool send(std::span<const uint8_t> bytes);

 private:
  int fd_ = -1;
};

}  // namespace mocap
