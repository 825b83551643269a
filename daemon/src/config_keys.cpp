// Every configuration key, declared once: one table per section. The loader (config.cpp) reads
// and range-checks each key through its entry, --print-config writes it, `mocapd --help` lists
// it and `mocapd --print-config-reference` writes docs/configuration.md's key reference from it
// (tests/daemon/test_config_keys.cpp checks the committed doc matches).
//
// Adding a key is one table entry: give the section struct in mocap/daemon/config.hpp (an
// output's section: mocap/outputs/outputs_config.hpp) its member with its default (the default
// lives there, and only there), then add an entry to the section's table below, e.g.
//     {.name = "port", .at = AT(port), .lo = 1, .hi = 65535, .help = "UDP port"},
// The member's type is the key's type (bool, int, uint64_t, double, std::string, an enum with
// `.choices`, an optional triple, a list of segment names); `.lo`/`.hi` are its range, `.unit`
// its unit, `.help` the docs' text; `.omit_default` for a key whose default means "absent",
// `.removed = "why"` for a key of a removed feature (accepted with a warning). A new enum type:
// an enum class with to_string(), and its `E& (*)(S&)` alternative in keys::Access. A new section:
// its struct, a table and `section<S>()` here, its declaration and one line in
// keys::for_each_section (config_keys.hpp). Then run scripts/update-config-doc (the docs' key
// reference is generated; a test compares). Filter keys are FilterParams members: they come from
// the filter module's own table (filter_param_names.hpp), not from here.
#include "config_keys.hpp"

#include <charconv>

#include "mocap/core/thread_priority.hpp"
#include "mocap/skeleton/config_tables.hpp"

namespace mocap::daemon::keys {

/// The accessor of member `m` of the section struct `S` (a type alias in scope).
#define AT(m)           \
  +[](S & s) -> auto& { \
    return s.m;         \
  }

std::string number_text(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::vector<std::string_view> split_choices(std::string_view choices) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < choices.size()) {
    while (i < choices.size() && (choices[i] == ',' || choices[i] == ' '))
      ++i;
    size_t j = i;
    while (j < choices.size() && choices[j] != ',' && choices[j] != ' ')
      ++j;
    if (j > i) out.push_back(choices.substr(i, j - i));
    i = j;
  }
  return out;
}

template <>
const Section<DaemonSection>& section() {
  using S = DaemonSection;
  static const Key<S> k[] = {
      {.name = "log_level",
       .at = AT(log_level),
       .choices = log_level_choices(),
       .help = "the daemon's log level (`--log-level` sets it too)"},
      {.name = "control_socket",
       .at = AT(control_socket),
       .help = "Unix socket for mocapctl (mode 0600); `\"\"` = `<runtime dir>/mocapd.sock`: "
               "`$XDG_RUNTIME_DIR`, else a private directory `/tmp/mocapd-<uid>` (created 0700, "
               "checked with lstat: ours, not a symlink, no access for others), else "
               "`~/.cache/mocapd`. Its directory also holds `mocapd.pid`, the instance lock: one "
               "mocapd per runtime directory; a second one says `already running (pid N)`, exits "
               "1 and touches no device, port or shared memory"},
  };
  static const Section<S> s{"daemon", "", k};
  return s;
}

template <>
const Section<PipelineConfig>& section() {
  using S = PipelineConfig;
  static const Key<S> k[] = {
      {.name = "rate_hz",
       .at = AT(rate_hz),
       .lo = 1,
       .hi = 2000,
       .unit = "Hz",
       .help = "pose frames per second at most, built from the latest state; a frame carries "
               "its newest sample's time and is skipped when no sample came since the last one "
               "(over 100 Hz sensors: 100 frames/s)"},
      {.name = "publish_every_sample",
       .at = AT(publish_every_sample),
       .help = "also publish a frame on every sample (lowest latency)"},
      {.name = "stale_after_ms",
       .at = AT(stale_after_ms),
       .lo = 10,
       .hi = 60000,
       .unit = "ms",
       .help = "a sensor silent this long is flagged stale; its segment is inferred"},
      {.name = "realtime_priority",
       .at = AT(realtime_priority),
       .lo = 0,
       .hi = kMaxRealtimePriority,
       .help = "SCHED_FIFO priority of the device readers, the pipeline and the JSON stream (0 = "
               "normal scheduling); keeps latency low while other programs load the CPU. Needs "
               "root, `CAP_SYS_NICE` or `LimitRTPRIO=` (see config/mocapd.service); if refused, a "
               "warning and normal scheduling"},
      {.name = "read_batch_ms",
       .at = AT(read_batch_ms),
       .lo = 0,
       .hi = 50,
       .unit = "ms",
       .help = "a device reader whose samples carry the device's own clock waits this long after "
               "a read before the next, so fast sensors are read in batches (a 1 kHz sensor: 250 "
               "reads/s instead of 1000); sensors slower than 1/this are read sample by sample "
               "anyway, and their samples' times come from the device, so only faster sensors' "
               "samples reach the frames up to this much later. 0 = read every sample at once; "
               "not used with publish_every_sample"},
  };
  static const Section<S> s{"pipeline", "", k};
  return s;
}

template <>
const Section<FilterConfig>& section() {
  using S = FilterConfig;
  static const Key<S> k[] = {
      {.name = "use_mag",
       .at = AT(use_mag),
       .help = "9-D orientation (magnetometer heading) or 6-D (each sensor's heading is then "
               "aligned on its own: at the N-pose calibration from its site's outward normal or "
               "the mounting motion, and from motion with its neighbours, docs/skeleton.md)"},
      {.name = "mag_local_field_hold_s",
       .removed = "a local field at the calibration is watched by the body tracker "
                  "(rig/local_field_watch.hpp), not the filter"},
      {.name = "mag_local_field_step_s",
       .removed = "a local field at the calibration is watched by the body tracker "
                  "(rig/local_field_watch.hpp), not the filter"},
  };
  static const Section<S> s{
      "filter",
      "Besides `use_mag`, every parameter of the attitude filter (`FilterParams` in "
      "filter/include/mocap/filter/filter_params.hpp, one struct per stage, where each one's "
      "meaning, unit and default are given; docs/filter.md) is a key, e.g. `tau_mag_s = 12`, "
      "`rest_th_gyr_deg_s = 1.5`; the last column names the member a key sets. "
      "--print-config writes those that differ from the filter's defaults.",
      k};
  return s;
}

template <>
const Section<BodyConfig>& section() {
  using S = BodyConfig;
  static const Key<S> k[] = {
      {.name = "model",
       .doc_type = "file path",
       .doc_default = "none",
       .help = "a body model file in the format of `config/body/default.toml` (`height_m`, "
               "`[segment.NAME]` offsets) read first; the keys of `[body]` override it"},
      {.name = "joint_limits",
       .doc_type = "file path",
       .doc_default = "none",
       .help = "a joint-limits file in the format of `config/body/joint_limits.toml` "
               "(`[joint.NAME]`) applied over the anatomical defaults (docs/skeleton.md); "
               "violations are reported, never imposed"},
      {.name = "height_m",
       .at = AT(model.height_m),
       .lo = kMinBodyHeightM,
       .hi = kMaxBodyHeightM,
       .unit = "m",
       .help = "body height; segment lengths follow anthropometric ratios (Winter)"},
      {.name = "segment",
       .doc_type = "tables",
       .doc_default = "none",
       .help = "`[body.segment.NAME]` tables: measured `joint_offset_m` and `end_offset_m` of a "
               "segment (example above)"},
      {.name = "joint",
       .doc_type = "tables",
       .doc_default = "none",
       .help = "`[body.joint.NAME]` tables: personal joint ranges `a_deg`, `b_deg`, "
               "`twist_deg`, `hinge`, `limited` (example above)"},
      {.name = "root_motion",
       .at = AT(root_motion),
       .help = "move the root with the stance foot (false: pelvis pinned)"},
      {.name = "enforce_limits",
       .removed = "joint limits are reported, never imposed: docs/skeleton.md"},
  };
  static const Section<S> s{
      "body",
      "Measured segment lengths and personal joint ranges go inline too, in the same keys as "
      "the files (metres and degrees, segment frames in the N-pose: x forward, y left, z up):\n"
      "\n"
      "```toml\n"
      "[body]\n"
      "height_m = 1.68\n"
      "[body.segment.forearm_l]          # any segment name\n"
      "joint_offset_m = [0, 0, -0.27]    # its joint (the elbow) in the parent's frame\n"
      "end_offset_m = [0, 0, -0.25]      # its tip in its own frame\n"
      "[body.joint.knee_l]               # joint or segment names (docs/skeleton.md, \"Joint "
      "limits\")\n"
      "b_deg = [-5, 130]                 # also a_deg, twist_deg; hinge, limited = true/false\n"
      "```\n"
      "\n"
      "Order: the model file, then `height_m` and `[body.segment.*]`; the defaults, then the\n"
      "`joint_limits` file, then `[body.joint.*]`. Paths are relative to the working "
      "directory.\n"
      "Errors in an included file name that file's line and the key that included it\n"
      "(`body.toml:4:16: end_offset_m must be an array of 3 numbers (included by rig.toml:2\n"
      "body.model)`). `--print-config` (and the configuration a recording stores) writes every\n"
      "override inline and no file keys, so a session carries its body with it (`mocap "
      "export`\n"
      "uses it for the BVH's offsets).",
      k};
  return s;
}

template <>
const Section<CalibrationConfig>& section() {
  using S = CalibrationConfig;
  static constexpr std::string_view kWorse =
      "it made tracking of real motion worse: docs/accuracy.md";
  static const Key<S> k[] = {
      {.name = "pose", .at = AT(pose), .choices = "npose, tpose", .help = "default pose"},
      {.name = "countdown_s",
       .at = AT(countdown_s),
       .lo = 0,
       .hi = 60,
       .unit = "s",
       .help = "seconds between `mocapctl calibrate` and the capture"},
      {.name = "capture_s",
       .at = AT(capture_s),
       .lo = 0.05,
       .hi = 10,
       .unit = "s",
       .help = "seconds of standing still averaged"},
      {.name = "file",
       .at = AT(file),
       .help = "calibration loaded at start if present; written (temporary file + atomic "
               "rename, by a writer thread off the pipeline) after each calibration and whenever "
               "a heading reset changes it, at most every 5 s"},
      {.name = "refine_hinges", .removed = kWorse},
      {.name = "heading_coupling", .removed = kWorse},
      {.name = "relative_mag_heading", .removed = kWorse},
      {.name = "heading",
       .at = AT(heading),
       .choices = "mount_normals, pelvis_sensor, mean_sensors",
       .help = "where the calibration's body heading (the direction the person faces) comes "
               "from. `mount_normals`: every sensor lies flat on its site with its z axis (after "
               "`axis_remap`) out of the skin; the heading is the circular mean over the sites' "
               "known outward normals (the standard sites of skeleton/sensor_sites.hpp, or each "
               "sensor's `site_normal`), so one strap's misalignment counts 1/N; without "
               "`filter.use_mag` each sensor's heading is aligned from its own site's normal. "
               "`pelvis_sensor`: the pelvis sensor's +x points forward (its misalignment becomes "
               "every mounting's yaw). `mean_sensors`: every sensor's +x points forward"},
  };
  static const Section<S> s{"calibration", "", k};
  return s;
}

template <>
const Section<JsonOutputConfig>& section() {
  using S = JsonOutputConfig;
  static const Key<S> k[] = {
      {.name = "enabled", .at = AT(enabled), .help = "pose JSON over TCP (docs/streaming.md)"},
      {.name = "bind",
       .at = AT(bind),
       .ipv4 = true,
       .help = "listening address (IPv4); loopback unless configured otherwise"},
      {.name = "port", .at = AT(port), .lo = 0, .hi = 65535, .help = "TCP port; 0 = any free port"},
      {.name = "max_clients",
       .at = AT(max_clients),
       .lo = 1,
       .hi = 1000,
       .help = "stream clients served at once; further connections are closed at once"},
      {.name = "unix_socket",
       .at = AT(unix_socket),
       .help = "absolute path: serve the stream on this Unix socket (mode 0600, private poses) "
               "instead of TCP; `\"\"` = TCP (docs/reliability.md, trust model)"},
  };
  static const Section<S> s{"outputs.json", "", k};
  return s;
}

template <>
const Section<VmcOutputConfig>& section() {
  using S = VmcOutputConfig;
  static const Key<S> k[] = {
      {.name = "enabled", .at = AT(enabled), .help = "VMC over OSC/UDP"},
      {.name = "host", .at = AT(host), .ipv4 = true, .help = "receiver's IPv4 address"},
      {.name = "port", .at = AT(port), .lo = 1, .hi = 65535, .help = "receiver's UDP port"},
  };
  static const Section<S> s{"outputs.vmc", "", k};
  return s;
}

template <>
const Section<VrchatOutputConfig>& section() {
  using S = VrchatOutputConfig;
  static const Key<S> k[] = {
      {.name = "enabled",
       .at = AT(enabled),
       .help = "VRChat OSC trackers over UDP (docs/streaming.md section 3)"},
      {.name = "host",
       .at = AT(host),
       .ipv4 = true,
       .help = "receiver's IPv4 address: the Quest's LAN address for a standalone headset"},
      {.name = "port", .at = AT(port), .lo = 1, .hi = 65535, .help = "receiver's UDP port"},
      {.name = "trackers",
       .at = AT(trackers),
       .lo = 1,
       .hi = 8,
       .help = "segment sent as tracker 1, 2, ...: 1 to 8 segment names, `\"\"` leaves a slot "
               "unsent"},
      {.name = "head",
       .at = AT(head),
       .help = "also send `/tracking/trackers/head/...` (VRChat aligns the trackers with the "
               "headset by it)"},
      {.name = "height_m",
       .at = AT(height_m),
       .lo = 0,
       .hi = 3,
       .unit = "m",
       .help = "the user's height as VRChat knows it; positions are scaled by `height_m / "
               "body.height_m`; 0 = unscaled"},
  };
  static const Section<S> s{"outputs.vrchat", "", k};
  return s;
}

template <>
const Section<PostureOutputConfig>& section() {
  using S = PostureOutputConfig;
  static const Key<S> k[] = {
      {.name = "enabled", .at = AT(enabled), .help = "shared memory for mocap-viewer"},
      {.name = "shm_name", .at = AT(shm_name), .help = "`\"\"` = `/mocap-posture-<uid>`"},
  };
  static const Section<S> s{"outputs.posture", "", k};
  return s;
}

template <>
const Section<RecordingConfig>& section() {
  using S = RecordingConfig;
  static const Key<S> k[] = {
      {.name = "directory",
       .at = AT(directory),
       .help = "where `mocapctl record start [NAME]` creates its files; names never leave it "
               "(no `..`, no symlinks, absolute names only inside it)"},
      {.name = "raw",
       .at = AT(raw),
       .help = "store raw device bytes (bit-exact replay through the drivers; "
               "docs/session-format.md)"},
      {.name = "samples", .at = AT(samples), .help = "store decoded samples"},
      {.name = "poses", .at = AT(poses), .help = "store published pose frames"},
      {.name = "auto_start",
       .at = AT(auto_start),
       .help = "start recording at startup into this name inside `directory`; never truncates: "
               "if it exists (a restart after a crash), `NAME-2.ext`, `NAME-3.ext`, ..."},
      {.name = "compression",
       .at = AT(compression),
       .choices = "none, zstd",
       .help = "block compression on the recorder's writer thread, never the pipeline's "
               "(docs/session-format.md; ratio and CPU: `mocap bench record`)"},
      {.name = "compression_level",
       .at = AT(compression_level),
       .lo = 1,
       .hi = 19,
       .help = "zstd level"},
  };
  static const Section<S> s{"recording", "", k};
  return s;
}

template <>
const Section<DemoConfig>& section() {
  using S = DemoConfig;
  static const Key<S> k[] = {
      {.name = "path",
       .at = AT(path),
       .choices = "device, direct",
       .help = "`device`: samples encoded and written to one pty per sensor, read by the real "
               "driver; `direct`: into the pipeline"},
      {.name = "protocol", .at = AT(protocol), .help = "wire protocol of the simulated devices"},
      {.name = "rate_hz",
       .at = AT(rate_hz),
       .lo = 1,
       .hi = 2000,
       .unit = "Hz",
       .help = "per-sensor rate"},
      {.name = "motion",
       .at = AT(motion),
       .help = "performer motion (npose, walk, turn, squat, arm_raise, reach, sequence), "
               "optionally prefixed by `calibrate+`: the calibration procedure first (the N-pose "
               "stand, then knee bends with elbow curls; docs/sim.md). Or a BVH file path "
               "(`\"take.bvh\"`, `\"calibrate+take.bvh\"`): the virtual sensors ride on its bones "
               "and the avatar takes its segment lengths (docs/sim.md; `mocap perform --bvh` "
               "writes one)"},
      {.name = "seed", .at = AT(seed), .lo = 0, .hi = 9223372036854775807.0, .help = "noise seed"},
      {.name = "gyro_scale_calibration",
       .at = AT(gyro_scale_calibration),
       .help = "the virtual sensors come with their one-time gyro scale calibration (each "
               "sensor's `gyr_scale` measured on its virtual table spins, as `mocap gyro-scale` "
               "does); false leaves the drawn ~0.5 % scale errors in"},
  };
  static const Section<S> s{
      "demo",
      "Used by `mocapd --demo`. The demo calibrates itself (N-pose) in each of the performer's "
      "stands; it shortens `calibration.countdown_s` so the capture fits the 3 s stand "
      "(docs/sim.md).",
      k};
  return s;
}

template <>
const Section<SensorConfig>& section() {
  using S = SensorConfig;
  static const Key<S> k[] = {
      {.name = "name",
       .at = AT(name),
       .doc_default = "required",
       .help = "1..23 bytes of ASCII letters, digits, `_`, `-` or non-ASCII UTF-8 characters "
               "(`José`; no spaces: control commands take it as one word), unique"},
      {.name = "driver",
       .at = AT(driver),
       .doc_default = "required",
       .help = "protocol: `witmotion`, `xbus`, `line`, `ds4`, `dualsense`, `joycon`"},
      {.name = "port",
       .at = AT(port),
       .omit_default = true,
       .help = "serial path, `/dev/serial/by-id/...`, or `udp:HOST:PORT`; or give `vid`+`pid`"},
      {.name = "vid",
       .at = AT(vid),
       .lo = 0,
       .hi = 0xFFFF,
       .omit_default = true,
       .doc_default = "none",
       .help = "USB vendor id (e.g. `0x054c`); with `pid`, instead of `port`"},
      {.name = "pid",
       .at = AT(pid),
       .lo = 0,
       .hi = 0xFFFF,
       .omit_default = true,
       .doc_default = "none",
       .help = "USB product id"},
      {.name = "serial",
       .at = AT(serial),
       .omit_default = true,
       .help = "USB serial number, to pick one of several identical devices"},
      {.name = "hid", .at = AT(hid), .omit_default = true, .help = "the device is a HID device"},
      {.name = "baud",
       .at = AT(baud),
       .lo = 0,
       .hi = 4000000,
       .help = "serial baud; 0 = protocol default"},
      {.name = "rate_hz",
       .at = AT(rate_hz),
       .lo = 0,
       .hi = 10000,
       .unit = "Hz",
       .help = "requested device rate; 0 = device default"},
      {.name = "segment",
       .at = AT(segment),
       .help = "segment it drives (pelvis, torso, neck, head, upper_arm_l, forearm_l, hand_l, "
               "..._r, thigh_l, shank_l, foot_l, ..._r)"},
      {.name = "axis_remap",
       .at = AT(axis_remap),
       .help = "sensor axes from device axes, e.g. `\"-y,x,z\"`"},
      {.name = "site_normal",
       .at = AT(site_normal),
       .omit_default = true,
       .direction = true,
       .doc_default = "the segment's standard site",
       .help = "outward normal of the skin where the sensor lies, body frame in the N-pose (x "
               "forward, y left, z up), e.g. `[0, 1, 0]` for the outside of the left arm; three "
               "numbers, not all zero. Standard sites: pelvis sacrum (back), torso sternum, neck "
               "back, head top, arms and hands on the outer side, thighs front turned 22 deg "
               "outward, shanks on the tibia, feet on the instep"},
      {.name = "gyr_scale",
       .at = AT(gyr_scale),
       .lo = 0.8,
       .hi = 1.2,
       .omit_default = true,
       .doc_default = "absent (uncalibrated)",
       .help = "the gyro's scale per sensor axis (after `axis_remap`) from its one-time "
               "table-spin calibration: print it with `mocap gyro-scale spins.mocapses` "
               "(docs/devices.md \"Gyro scale calibration\"); samples are divided by it"},
      {.name = "log_level",
       .at = AT(log_level),
       .choices = log_level_choices(),
       .help = "this device's log level"},
      {.name = "options",
       .doc_type = "table",
       .doc_default = "none",
       .help = "`[sensor.options]`: protocol options (strings, numbers, booleans), e.g. "
               "`quat_order = \"wxyz\"`"},
  };
  static const Section<S> s{"sensor", "One `[[sensor]]` table per sensor.", k};
  return s;
}

#undef AT

}  // namespace mocap::daemon::keys
