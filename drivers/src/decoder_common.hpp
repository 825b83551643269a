// What every protocol decoder shares after parsing: stats, the sensor id, the axis remap, the
// device clock, and the final checks before a sample leaves the driver (finite values only).
#pragma once

#include <cstdint>

#include "mocap/drivers/axis_remap.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/drivers/device_clock.hpp"

namespace mocap {

/// A StreamDecoder that also reports replies to host commands (used by device set-up steps).
class ProtocolDecoder : public StreamDecoder {
 public:
  /// How many replies with this protocol-specific id were seen (e.g. Xbus MID, Joy-Con subcmd).
  virtual uint64_t replies(uint32_t /*id*/) const { return 0; }
};

/// A sensor's full scale per axis (the largest reading it can make), for the plausibility check.
/// spec.options gyr_range_dps / acc_range_g override the protocol's.
struct SensorRange {
  double gyr_dps = 2000;
  double acc_g = 16;
};

class DecoderCommon {
 public:
  explicit DecoderCommon(const DeviceSpec& spec, SensorRange range = {});

  /// Maps device time to host time, remaps axes, drops non-finite fields, stamps id and emits.
  /// s holds device-frame SI values; dropped = samples lost just before this one.
  void emit(ImuSample& s, int64_t t_device_ns, int64_t t_read_ns, int64_t dropped,
            SampleSink& sink);
  /// Emits with host read time as the sample time (devices without a clock).
  void emit_untimed(ImuSample& s, int64_t t_read_ns, SampleSink& sink);
  /// The next sample's ImuSample::seq is the device's own counter `seq` (e.g. a packet number);
  /// without this call samples are counted (gaps included).
  void set_next_seq(uint32_t seq) { seq_ = seq; }

  DecoderStats stats;
  uint16_t sensor_id = 0;

 private:
  void finish(ImuSample& s, SampleSink& sink);
  void check_range(ImuSample& s);
  double gyr_max_rad_s_, acc_max_m_s2_;
  AxisRemap remap_;
  DeviceClock clock_;
  uint32_t seq_ = 0;
  int64_t first_read_ns_ = -1;
  int64_t last_host_ns_ = INT64_MIN;
};

/// Reads a numeric option from spec.options (fallback when absent); throws invalid_argument
/// naming the option when malformed.
double option_double(const DeviceSpec& spec, const char* key, double fallback);
std::string option_string(const DeviceSpec& spec, const char* key, const char* fallback);

}  // namespace mocap
