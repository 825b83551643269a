// The daemon configuration: one TOML file (sensors, filter, body, calibration, outputs,
// recording) loaded into plain structs. Loading validates everything up front and reports every
// problem as "file:line:column: key: message", so the daemon never starts half-configured.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/outputs/outputs_config.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap::daemon {

// The keys' ranges, units and help text are in daemon/src/config_keys.cpp (one table per
// section); the structs below hold each key's value and its default.

/// One sensor of the rig (one device carrying one IMU).
struct SensorConfig {
  std::string name;        ///< unique in the rig; shown in status and streams
  std::string driver;      ///< protocol ("witmotion", "xbus", "ds4", "line", ...)
  std::string port;        ///< serial path, "udp:HOST:PORT", or empty when vid/pid given
  int vid = -1, pid = -1;  ///< USB ids (then port becomes "usb:VID:PID[:SERIAL]")
  std::string serial;      ///< USB serial number to pick one of several identical devices
  bool hid = false;        ///< the device is a HID device ("hid:VID:PID")
  int baud = 0;            ///< 0 = the protocol's default
  double rate_hz = 0;      ///< requested device output rate (0 = device default)
  std::string segment;     ///< body segment it drives ("" = not attached)
  std::string axis_remap = "x,y,z";
  /// Outward normal of the skin where the sensor lies (body frame in the N-pose: x forward,
  /// y left, z up) when it is not the segment's standard site (skeleton/sensor_sites.hpp); the
  /// sensor's z axis (after axis_remap) lies along it. Used by calibration.heading =
  /// "mount_normals".
  std::optional<std::array<double, 3>> site_normal;
  /// Gyro scale per axis (after axis_remap), from the one-time table-spin calibration (`mocap
  /// gyro-scale`): the gyro reads scale * rate, so samples are divided by it. Absent:
  /// uncalibrated (the skeleton then expects the gyros' scale errors after turns).
  std::optional<std::array<double, 3>> gyr_scale;
  LogLevel log_level = LogLevel::info;
  std::map<std::string, std::string> options;  ///< protocol options
};

/// Attitude filter settings: use_mag, plus the filter's parameters (file keys: the FilterParams
/// member names, e.g. tau_mag_s = 12).
struct FilterConfig {
  bool use_mag = true;  ///< 9-D (magnetometer heading) or 6-D orientation
  FilterParams params;
};

struct BodyConfig {
  /// Height and per-segment offsets (file keys: height_m, [body.segment.NAME], and `model`, a
  /// body file as config/body/default.toml read first; the inline keys override it).
  BodyModelConfig model;
  /// Joint limits: the anatomical defaults, then the `joint_limits` file's [joint.NAME]
  /// overrides (as config/body/joint_limits.toml), then the inline [body.joint.NAME] tables.
  JointLimits limits = default_joint_limits();
  bool root_motion = true;  ///< stance-foot root translation
};

struct CalibrationConfig {
  CalibrationPose pose = CalibrationPose::npose;
  double countdown_s = 3.0;  ///< seconds from the command to the capture
  double capture_s = 1.0;    ///< seconds averaged during the capture
  std::string file;          ///< saved calibration loaded at start, written after each one
  /// Where the calibration's body heading comes from: "mount_normals" (every sensor lies flat
  /// on its site with z out of the skin; the heading is the circular mean over the sites'
  /// normals, so one sensor's misalignment counts 1/N), "pelvis_sensor" (the pelvis sensor's
  /// heading_axis_sensor points forward) or "mean_sensors" (that axis of every sensor does).
  HeadingSource heading = HeadingSource::mount_normals;
  /// Body forward (+x) in the pelvis sensor's frame: the heading axis of a pelvis_sensor or
  /// mean_sensors calibration. Not a file key: the default suits a pelvis sensor worn with +x
  /// forward; the demo sets its performer's belt-clip axis.
  std::array<double, 3> heading_axis_sensor{1.0, 0.0, 0.0};
};

struct PipelineConfig {
  double rate_hz = 120.0;             ///< pose frame rate
  bool publish_every_sample = false;  ///< also publish a frame on every sample (low latency)
  double stale_after_ms = 250.0;      ///< a sensor silent this long degrades its segment
  /// SCHED_FIFO priority (1..49) of the device readers, the pipeline and the pose stream; 0 =
  /// normal scheduling. Keeps the latency low on a busy machine (needs CAP_SYS_NICE/LimitRTPRIO).
  int realtime_priority = 0;
  /// A device reader whose samples carry the device's own time waits this long after a read
  /// before the next (so a 1 kHz sensor is read in batches, not 1000 times a second); 0 = read
  /// every sample at once. Not used with publish_every_sample.
  double read_batch_ms = 4.0;
};

// The [outputs.*] and [recording] sections: each output's options struct lives with the outputs.
using outputs::JsonOutputConfig;
using outputs::OutputsConfig;
using outputs::PostureOutputConfig;
using outputs::RecordingConfig;
using outputs::VmcOutputConfig;
using outputs::VrchatOutputConfig;

struct DaemonSection {
  LogLevel log_level = LogLevel::info;
  std::string control_socket;  ///< "" = "$XDG_RUNTIME_DIR/mocapd.sock"
};

/// How the demo's samples reach the pipeline: through simulated devices on ptys and the real
/// drivers, or directly.
enum class DemoPath : uint8_t { device, direct };
std::string_view to_string(DemoPath p);

struct DemoConfig {
  DemoPath path = DemoPath::device;
  std::string protocol = "witmotion";  ///< wire protocol the simulated devices speak
  double rate_hz = 100.0;
  /// A virtual-performer motion (sim::motion_names() or a BVH file, optionally "calibrate+"):
  /// by default the calibration procedure (N-pose, knee bends with elbow curls) before the
  /// sequence.
  std::string motion = "calibrate+sequence";
  uint64_t seed = 1;
  /// The virtual sensors come with their one-time gyro scale calibration (`mocap gyro-scale`,
  /// done on their virtual table spins): each sensor's gyr_scale is set.
  bool gyro_scale_calibration = true;
};

struct Config {
  std::string source;  ///< file it came from ("" for defaults)
  DaemonSection daemon;
  PipelineConfig pipeline;
  FilterConfig filter;
  BodyConfig body;
  CalibrationConfig calibration;
  OutputsConfig outputs;
  RecordingConfig recording;
  DemoConfig demo;
  std::vector<SensorConfig> sensors;
};

/// Limits of a configuration: its size, the problems reported before checking stops, and the
/// length of a key or message in a report (longer ones are cut, never echoed whole).
inline constexpr std::size_t kMaxConfigBytes = 1u << 20;
inline constexpr std::size_t kMaxConfigErrors = 50;
inline constexpr std::size_t kMaxConfigMessageKey = 120;
inline constexpr std::size_t kMaxConfigMessage = 300;
/// `s` if at most `max` bytes, else its start and how many bytes were left out.
std::string cut_for_message(std::string_view s, std::size_t max);

/// A problem found while loading: where, which key, what.
struct ConfigError {
  std::string file;
  int line = 0, column = 0;  ///< 1-based; 0 when unknown
  std::string key;           ///< dotted path, e.g. "sensor[2].segment"
  std::string message;
  std::string to_string() const;
};

/// Thrown by load_config when the configuration is not valid; holds every problem found.
struct ConfigErrors {
  std::vector<ConfigError> errors;
  /// Keys of removed features, accepted and ignored so that older configs and recordings still
  /// load: one line each naming the key (printed by mocapd; not an error).
  std::vector<std::string> warnings;
  std::string to_string() const;  ///< one line per error
};

/// Checks that need the drivers; each returns "" or a message. The loader
/// reports a message at the offending key's position.
struct ConfigValidators {
  std::function<std::string(const SensorConfig&)> sensor;  ///< e.g. unknown driver or option
  /// A sensor that loads but will not work as asked (e.g. a rate its baud cannot carry): ""
  /// or a warning, reported in ConfigErrors::warnings.
  std::function<std::string(const SensorConfig&)> sensor_warning;
};
/// The real checks: drivers' make_decoder.
const ConfigValidators& default_validators();

/// Parses and validates TOML text. `overrides` are "key.path=VALUE" strings (from --set),
/// applied before validation; VALUE is a TOML value, or a bare string. Returns the config or
/// fills `errors` (never a partial config).
std::optional<Config> parse_config(std::string_view toml_text, std::string_view source_name,
                                   const std::vector<std::string>& overrides, ConfigErrors& errors,
                                   const ConfigValidators* validators = nullptr);
/// Reads the file, then parse_config.
std::optional<Config> load_config(const std::string& path,
                                  const std::vector<std::string>& overrides, ConfigErrors& errors,
                                  const ConfigValidators* validators = nullptr);
/// The effective configuration (defaults included) as TOML text that parse_config accepts.
std::string config_to_toml(const Config& c);
/// `c` with KEY=VALUE overrides applied (as --set does to a file): a recorded or derived
/// configuration changed from the command line. nullopt with the problems in `errors`.
std::optional<Config> with_overrides(const Config& c, const std::vector<std::string>& sets,
                                     std::string_view source_name, ConfigErrors& errors);

/// Levenshtein distance (for "did you mean" suggestions).
int edit_distance(std::string_view a, std::string_view b);
/// The candidate nearest to `word`, or "" if none is plausibly meant.
std::string nearest_name(std::string_view word, const std::vector<std::string_view>& candidates);

/// The key reference of docs/configuration.md (markdown: one table per section), written from
/// the key tables (`mocapd --print-config-reference`).
std::string config_reference_markdown();
/// The keys by section, one line each, for `mocapd --help`.
std::string config_key_summary();
/// "<runtime dir>/mocapd.sock": $XDG_RUNTIME_DIR, else a private 0700 directory
/// (mocap/core/runtime_dir.hpp). Throws std::runtime_error when there is none.
std::string default_control_socket();

}  // namespace mocap::daemon
