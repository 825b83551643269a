// The contract between drivers and their users (the daemon, `mocap simulate` tests, replay):
//   - a StreamDecoder turns timestamped byte chunks into ImuSamples; it is pure and
//     deterministic (no clocks, no I/O), so recorded raw bytes replay bit-identically;
//   - a Device owns a transport and one reader thread that reads, timestamps at read, decodes
//     and hands samples to a SampleSink; it reconnects by itself when the device vanishes.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "mocap/core/imu_sample.hpp"
#include "mocap/core/log.hpp"
#include "mocap/drivers/sensor_telemetry.hpp"

namespace mocap {

/// Resets a sensor can ask for: a full one (the rig's calibration pose) or the heading only.
enum class ResetRequest : uint8_t { full, heading };

/// What a device's reader thread reports. Called from that thread only: implementations must
/// be quick and must not block (push into a lock-free ring and return).
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  /// A decoded, unit-converted sample (sensor frame, SI units, host time).
  virtual void on_sample(const ImuSample& sample) = 0;
  /// Raw bytes as read from the transport, with the host time of the read (for recording).
  virtual void on_raw(uint16_t /*device_index*/, int64_t /*t_host_ns*/,
                      std::span<const uint8_t> /*bytes*/) {}
  /// Connection state changes: connected = false when the device vanished (with a reason).
  virtual void on_connection(uint16_t /*device_index*/, bool /*connected*/,
                             std::string_view /*reason*/) {}
  /// A sensor asked for a reset (a SlimeVR tracker's button: packet 21). Quick, non-blocking.
  virtual void on_reset_request(uint16_t /*device_index*/, ResetRequest /*what*/) {}
  /// What a sensor reports about itself (battery, signal, temperature, identity), whole, each
  /// time a value changes; sensor_id as on its samples. Quick, non-blocking (a short lock).
  virtual void on_telemetry(uint16_t /*sensor_id*/, const SensorTelemetry& /*telemetry*/) {}
};

/// How to reach and decode one device. Parsed from the daemon config; also built by tests.
struct DeviceSpec {
  std::string name;      ///< unique name from the rig, e.g. "wt901_left_arm"
  std::string protocol;  ///< "witmotion", "xbus", "ds4", "dualsense", "joycon", "line", "slimevr"
  /// Where: a serial path ("/dev/ttyUSB0", "/dev/pts/3"), "usb:VID:PID[:SERIAL]" for a serial
  /// adapter or raw USB device found by ids, "hid:VID:PID[:SERIAL]", or "udp:HOST:PORT" to bind.
  std::string port;
  int baud = 0;                  ///< serial baud (0 = the protocol's default)
  double rate_hz = 0;            ///< requested output rate (0 = the device's default)
  uint16_t device_index = 0;     ///< index of this device in the rig (for on_raw/on_connection)
  uint16_t first_sensor_id = 0;  ///< sensor_id stamped on samples (+ n for multi-sensor devices)
  /// Axis remap applied after unit conversion: sensor axis i = sign * device axis index.
  /// Written like "x,y,z" (identity) or "-y,x,z".
  std::string axis_remap = "x,y,z";
  std::map<std::string, std::string> options;  ///< protocol-specific (e.g. "quat_order")
  /// SCHED_FIFO priority of the reader thread (0 = normal scheduling); see
  /// mocap/core/thread_priority.hpp. Not granted: a warning, and the device runs anyway.
  int realtime_priority = 0;
  /// Reader batching: after a read whose samples all carried the device's own time (their
  /// times do not depend on when they are read), the reader waits until this long after that
  /// read before reading again. 0 = read as soon as bytes arrive. Untimed samples (stamped at
  /// read) are always read at once.
  int64_t read_batch_ns = 0;
};

/// Counters every decoder and device keeps (monotonic, never reset while running).
struct DecoderStats {
  uint64_t bytes = 0;            ///< bytes fed
  uint64_t frames = 0;           ///< frames that passed framing and checksum
  uint64_t samples = 0;          ///< ImuSamples emitted
  uint64_t timed_samples = 0;    ///< of them, timed by the device's clock (not at read)
  uint64_t checksum_errors = 0;  ///< frames dropped for a bad checksum
  uint64_t resyncs = 0;          ///< times the framer skipped garbage to find a frame start
  uint64_t dropped_samples = 0;  ///< samples missing according to the device's counter
  uint64_t clock_resets = 0;     ///< device clock jumps / restarts detected
  /// Samples with a gyro or accelerometer axis beyond 1.1 x the sensor's full scale: impossible
  /// readings behind a valid checksum; the field is dropped and the sample flagged
  /// kFlagImplausible (docs/devices.md "Implausible values").
  uint64_t implausible = 0;
  /// Samples with an axis at >= 0.99 x full scale (clipped, or a glitch): kept, kFlagSaturated.
  uint64_t saturated = 0;
};

/// Pure byte-stream decoder for one protocol (framing + parse + unit conversion + time mapping).
class StreamDecoder {
 public:
  virtual ~StreamDecoder() = default;
  /// Feeds bytes read at host time t_host_ns; emits zero or more samples to sink.on_sample.
  virtual void feed(std::span<const uint8_t> bytes, int64_t t_host_ns, SampleSink& sink) = 0;
  virtual const DecoderStats& stats() const = 0;
};

struct DeviceStats {
  DecoderStats decoder;
  uint64_t reconnects = 0;  ///< successful reopenings after the device vanished
  bool connected = false;
  std::string last_error;
};

/// A live device: transport + reader thread + decoder.
class Device {
 public:
  virtual ~Device() = default;
  /// Opens the transport (or keeps retrying in the background) and starts the reader thread.
  virtual void start(SampleSink& sink) = 0;
  /// Stops the thread and closes the transport. Idempotent.
  virtual void stop() = 0;
  virtual DeviceStats stats() const = 0;
  virtual const DeviceSpec& spec() const = 0;
};

/// Factories (drivers/src/registry.cpp). Throw std::invalid_argument with a clear message for an
/// unknown protocol or malformed spec.
std::unique_ptr<StreamDecoder> make_decoder(const DeviceSpec& spec);
/// Whether the protocol's devices compute their orientation themselves, keep computing it
/// through a silence of the link and flag their restarts (kFlagDeviceRestarted): SlimeVR over
/// UDP. false for an unknown protocol.
bool fused_on_device(std::string_view protocol);
/// For a serial sensor whose rate x bytes per sample x bits per byte (10 for 8N1, 11 for 8N2)
/// exceeds its baud: a message saying so and what to change; "" otherwise (or when the
/// protocol's sample size or the rate is not known, or the port is not a serial link).
std::string serial_link_warning(const DeviceSpec& spec);
std::unique_ptr<Device> make_device(const DeviceSpec& spec, Logger log);

class ByteTransport;
/// make_device() with an explicit transport factory (simulated transports, tests).
std::unique_ptr<Device> make_device_with_transport(
    const DeviceSpec& spec, Logger log,
    std::function<std::unique_ptr<ByteTransport>(std::string& err)> open);

}  // namespace mocap
