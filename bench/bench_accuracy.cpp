// mocap bench accuracy: the virtual performer through the whole pipeline (sensor model ->
// AttitudeFilter per sensor -> N-pose calibration -> skeleton FK + root motion) for each motion,
// with and without magnetic disturbances. Prints JSON (per-joint angle RMSE, segment orientation
// RMSE, root drift vs ground truth) and, with --markdown, the table for docs/accuracy.md.
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "bench.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/sim/accuracy.hpp"
#include "mocap/sim/motion.hpp"

namespace mocap::bench {
namespace {

constexpr double kHingeTargetDeg = 2.0, kThreeDofTargetDeg = 3.0, kRootDriftTarget = 0.05;

std::vector<std::string> expand(const std::string& v, const std::vector<std::string>& all) {
  if (v == "all") return all;
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= v.size()) {
    const size_t comma = v.find(',', start);
    out.push_back(v.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

nlohmann::json to_json(const sim::AccuracyResult& r) {
  nlohmann::json j;
  j["motion"] = r.motion;
  j["disturbance"] = r.disturbance;
  j["calibrated"] = r.calibrated;
  j["calibration_message"] = r.calibration_message;
  if (!r.calibrated) return j;
  j["frames"] = r.frames;
  j["evaluated_s"] = r.evaluated_s;
  nlohmann::json joints, segments;
  for (int s = 0; s < kSegmentCount; ++s) {
    segments[std::string(kSegmentNames[s])] = r.segment_rmse_deg[s];
    if (s > 0) joints[std::string(kJointNames[s])] = r.joint_rmse_deg[s];
  }
  j["joint_rmse_deg"] = joints;
  j["segment_rmse_deg"] = segments;
  j["hinge_max_rmse_deg"] = r.hinge_max_rmse_deg;
  j["three_dof_max_rmse_deg"] = r.three_dof_max_rmse_deg;
  j["inferred_neck_max_rmse_deg"] = r.inferred_max_rmse_deg;
  j["segment_mean_rmse_deg"] = r.segment_mean_rmse_deg;
  nlohmann::json diag;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (r.sensor_inclination_rmse_deg[s] == 0 && r.sensor_heading_drift_deg[s] == 0) continue;
    diag[std::string(kSegmentNames[s])] = {
        {"npose_mount_yaw_error_deg", r.npose_mount_yaw_error_deg[s]},
        {"mount_yaw_error_deg", r.mount_yaw_error_deg[s]},
        {"filter_heading_drift_deg", r.sensor_heading_drift_deg[s]},
        {"filter_inclination_rmse_deg", r.sensor_inclination_rmse_deg[s]},
        {"mag_disturbed_fraction", r.sensor_mag_disturbed_fraction[s]},
        {"reference_imposed", r.sensor_ref_imposed[s]},
        {"anchor_trust_deg", r.sensor_anchor_trust_deg[s]}};
  }
  j["sensor_diagnostics"] = diag;
  j["hinges_identified"] = r.hinges_identified;
  for (size_t h = 0; h < r.hinges.size(); ++h) {
    const HingeEstimate& e = r.hinges[h];
    const RefinePair& pr = kRefinePairs[h];
    const std::string key = std::string(name(pr.parent)) + "-" + std::string(name(pr.child));
    j["hinge_refinement"][key] = {{"valid", e.valid},
                                  {"travel_deg", e.travel_deg},
                                  {"parent_yaw_deg", e.parent_yaw_deg},
                                  {"child_yaw_deg", e.child_yaw_deg},
                                  {"applied_child_yaw_deg", e.applied_child_yaw_deg},
                                  {"rms_residual", e.rms_residual},
                                  {"parent_travel_deg", e.parent_travel_deg},
                                  {"parent_valid", e.parent_valid}};
  }
  for (size_t h = 0; h < r.coupling.size(); ++h) {
    const CouplingHinge& c = r.coupling[h];
    const CouplingPair& pr = kCouplingPairs[h];
    const std::string key = std::string(name(pr.parent)) + "-" + std::string(name(pr.child));
    j["heading_coupling"][key] = {{"offset_deg", c.offset_deg},
                                  {"last_residual_deg", c.last_residual_deg},
                                  {"observed_s", c.observed_s}};
  }
  j["root_drift_m"] = r.root_drift_m;
  j["root_max_error_m"] = r.root_max_error_m;
  j["distance_walked_m"] = r.distance_walked_m;
  if (r.distance_walked_m >= 1.0) j["root_drift_percent"] = 100 * r.root_drift_fraction;
  j["targets"] = {{"hinge_le_2deg", r.hinge_max_rmse_deg <= kHingeTargetDeg},
                  {"three_dof_le_3deg", r.three_dof_max_rmse_deg <= kThreeDofTargetDeg},
                  {"root_drift_le_5pct",
                   r.distance_walked_m < 1.0 || r.root_drift_fraction <= kRootDriftTarget}};
  return j;
}

/// Ideal sensors plus the named default error groups (comma list); `bad` gets an unknown name.
sim::SensorModelParams only_errors(const std::string& list, std::string& bad) {
  const sim::SensorModelParams d;
  sim::SensorModelParams p = sim::SensorModelParams::ideal();
  for (const std::string& g : expand(list, {})) {
    if (g == "mount") {
      p.mount_misalignment_deg = d.mount_misalignment_deg;
    } else if (g == "mag") {
      p.mag_noise_uT = d.mag_noise_uT;
      p.mag_hard_iron_sigma_uT = d.mag_hard_iron_sigma_uT;
      p.mag_scale_sigma = d.mag_scale_sigma;
    } else if (g == "mag_hard_iron") {
      p.mag_hard_iron_sigma_uT = d.mag_hard_iron_sigma_uT;
    } else if (g == "mag_scale") {
      p.mag_scale_sigma = d.mag_scale_sigma;
    } else if (g == "mag_noise") {
      p.mag_noise_uT = d.mag_noise_uT;
    } else if (g == "gyr") {
      p.gyr_noise_density_dps_rthz = d.gyr_noise_density_dps_rthz;
      p.gyr_bias_sigma_dps = d.gyr_bias_sigma_dps;
      p.gyr_bias_walk_dps_rts = d.gyr_bias_walk_dps_rts;
      p.gyr_scale_sigma = d.gyr_scale_sigma;
    } else if (g == "acc") {
      p.acc_noise_density_m_s2_rthz = d.acc_noise_density_m_s2_rthz;
      p.acc_bias_sigma_m_s2 = d.acc_bias_sigma_m_s2;
      p.acc_scale_sigma = d.acc_scale_sigma;
    } else if (g == "timing") {
      p.jitter_sigma_s = d.jitter_sigma_s;
      p.drop_probability = d.drop_probability;
    } else if (!g.empty()) {
      bad = g;
    }
  }
  return p;
}

void print_markdown_row(const sim::AccuracyResult& r) {
  if (!r.calibrated) {
    std::fprintf(stderr, "| %s | %s | calibration refused: %s |\n", r.motion.c_str(),
                 r.disturbance.c_str(), r.calibration_message.c_str());
    return;
  }
  char drift[64];
  if (r.distance_walked_m >= 1.0)
    std::snprintf(drift, sizeof drift, "%.2f m / %.1f m = %.1f%%", r.root_drift_m,
                  r.distance_walked_m, 100 * r.root_drift_fraction);
  else
    std::snprintf(drift, sizeof drift, "%.2f m (not walking)", r.root_drift_m);
  std::fprintf(stderr, "| %s | %s | %.2f | %.2f | %.2f | %.2f | %s |\n", r.motion.c_str(),
               r.disturbance.c_str(), r.hinge_max_rmse_deg, r.three_dof_max_rmse_deg,
               r.inferred_max_rmse_deg, r.segment_mean_rmse_deg, drift);
}

/// Applies a comma list of name=value overrides to the named fields; false (with a message
/// naming the option and the entry) on an unknown name or a bad number.
/// An on|off option (absent: the default already in `out`); false after printing an error.
bool on_off(const CliArgs& args, const char* name, bool& out) {
  if (!args.has(name)) return true;
  const std::string v = args.get_or(name, "");
  if (v != "on" && v != "off") {
    std::fprintf(stderr, "mocap bench accuracy: --%s must be on or off\n", name);
    return false;
  }
  out = v == "on";
  return true;
}

bool set_params(const std::string& list, const char* option,
                std::initializer_list<std::pair<std::string_view, double*>> fields) {
  for (const std::string& kv : expand(list, {})) {
    if (kv.empty()) continue;
    const size_t eq = kv.find('=');
    double* field = nullptr;
    for (const auto& [name, ptr] : fields)
      if (eq != std::string::npos && kv.compare(0, eq, name) == 0 && name.size() == eq) field = ptr;
    char* end = nullptr;
    const double v = eq == std::string::npos ? 0 : std::strtod(kv.c_str() + eq + 1, &end);
    if (!field || !end || end == kv.c_str() + eq + 1 || *end != '\0') {
      std::fprintf(stderr, "mocap bench accuracy: bad --%s '%s'\n", option, kv.c_str());
      return false;
    }
    *field = v;
  }
  return true;
}

}  // namespace

int run_accuracy(int argc, char** argv) {
  CliArgs args;
  args.option("motion", "motion name, comma list or 'all' (default all)")
      .option("disturbance", "none|magnet|desk|both, comma list or 'all' (default none,both)")
      .option("seed", "random seed (default 1)")
      .option("rate", "sensor rate in Hz (default 100)")
      .option(
          "heading",
          "calibration heading source: normals|pelvis|mean|truth (default normals, as the daemon)")
      .flag(
          "calibration-moves",
          "calibrate with N-pose + calibration moves (knee bends, elbow curls) before each motion")
      .flag("gyro-scale-calibration",
            "calibrate each sensor's gyro scale first (table spins, as a user does once per "
            "sensor) and divide it out")
      .flag("warmup",
            "the sensors run for 22 s of walking and turning before the calibration stand")
      .option("filter-param", "AttitudeFilter overrides, comma list of name=value")
      .option("coupling", "heading coupling at knees/elbows: on|off (default on)")
      .option("relative-mag",
              "relative magnetometer heading smoothing: on|off (default on, as the daemon)")
      .option("relative-mag-param",
              "RelativeMagHeadingOptions overrides, comma list of name=value "
              "(tau_s, turn_deg, turn_memory_s, turn_tau_s)")
      .option("anchor",
              "filter heading anchored at the calibration: on|off (default on, as the daemon)")
      .option("consensus",
              "rig consensus of the reference field: on|off (default on, as the daemon)")
      .option("coupling-param",
              "HeadingCouplingOptions overrides, comma list of name=value "
              "(tau_s, min_flex_deg, min_axis_horizontal, "
              "max_elevation_mismatch, max_correction_deg, max_residual_deg)")
      .flag("no-carry", "heading coupling: do not carry a child's correction to the next segment")
      .flag("no-refine", "N-pose calibration only (no hinge-motion refinement)")
      .option("refine-param",
              "HingeRefineOptions overrides, comma list of name=value (min_travel_deg, "
              "max_yaw_deg, min_rate_deg_s, via_still_fraction, "
              "min_parent_off_axis_deg, basin_margin, direction_fraction, noise_weighting (0|1), "
              "block_min_samples, block_noise_floor)")
      .option("sensor-errors",
              "only these consumer-MEMS error groups, comma list of mount,mag,gyr,acc,timing "
              "(mag = mag_hard_iron + mag_scale + mag_noise; error breakdown; default all)")
      .flag("ideal", "ideal sensors (no noise, bias, misalignment): isolates the pipeline")
      .flag("markdown", "also print a markdown table on stderr");
  if (!args.parse(argc, argv, 1)) {
    std::fprintf(stderr, "mocap bench accuracy: %s\noptions:\n%s", args.error().c_str(),
                 args.help().c_str());
    return 2;
  }
  std::vector<std::string> all_motions;
  for (auto n : sim::motion_names())
    if (n != "npose") all_motions.emplace_back(n);
  sim::AccuracyOptions base;
  long seed = 1;
  if (!args.get_int("seed", seed) || !args.get_double("rate", base.rate_hz)) {
    std::fprintf(stderr, "mocap bench accuracy: %s\n", args.error().c_str());
    return 2;
  }
  base.seed = static_cast<uint64_t>(seed);
  const std::string heading = args.get_or("heading", "normals");
  if (heading == "normals")
    base.heading = HeadingSource::mount_normals;
  else if (heading == "pelvis")
    base.heading = HeadingSource::pelvis_sensor;
  else if (heading == "mean")
    base.heading = HeadingSource::mean_sensors;
  else if (heading == "truth")
    base.heading = HeadingSource::explicit_heading;
  else {
    std::fprintf(stderr,
                 "mocap bench accuracy: --heading must be normals, pelvis, mean or truth\n");
    return 2;
  }
  if (args.has("no-refine")) base.hinge_refine.enabled = false;
  if (args.has("gyro-scale-calibration")) base.gyro_scale_calibration = true;
  if (!on_off(args, "coupling", base.heading_coupling.enabled) ||
      !on_off(args, "relative-mag", base.relative_mag_heading.enabled) ||
      !on_off(args, "anchor", base.anchor_heading) ||
      !on_off(args, "consensus", base.rig_consensus))
    return 2;
  HeadingCouplingOptions& c = base.heading_coupling;
  if (!set_params(args.get_or("coupling-param", ""), "coupling-param",
                  {{"tau_s", &c.tau_s},
                   {"min_flex_deg", &c.min_flex_deg},
                   {"min_axis_horizontal", &c.min_axis_horizontal},
                   {"max_elevation_mismatch", &c.max_elevation_mismatch},
                   {"max_correction_deg", &c.max_correction_deg},
                   {"max_residual_deg", &c.max_residual_deg},
                   {"disturbed_weight", &c.disturbed_weight}}))
    return 2;
  if (args.has("no-carry")) base.heading_coupling.carry_distal = false;
  RelativeMagHeadingOptions& rm = base.relative_mag_heading;
  if (!set_params(args.get_or("relative-mag-param", ""), "relative-mag-param",
                  {{"tau_s", &rm.tau_s},
                   {"turn_deg", &rm.turn_deg},
                   {"turn_memory_s", &rm.turn_memory_s},
                   {"turn_tau_s", &rm.turn_tau_s}}))
    return 2;
  HingeRefineOptions& h = base.hinge_refine;
  double noise_weighting = h.noise_weighting ? 1 : 0;
  double block_min_samples = h.block_min_samples;
  if (!set_params(args.get_or("refine-param", ""), "refine-param",
                  {{"noise_weighting", &noise_weighting},
                   {"block_min_samples", &block_min_samples},
                   {"block_noise_floor", &h.block_noise_floor},
                   {"min_travel_deg", &h.min_travel_deg},
                   {"max_yaw_deg", &h.max_yaw_deg},
                   {"min_rate_deg_s", &h.min_rate_deg_s},
                   {"via_still_fraction", &h.via_still_fraction},
                   {"direction_fraction", &h.direction_fraction},
                   {"min_parent_off_axis_deg", &h.min_parent_off_axis_deg},
                   {"basin_margin", &h.basin_margin}}))
    return 2;
  h.noise_weighting = noise_weighting != 0;
  h.block_min_samples = static_cast<int>(block_min_samples);
  if (args.has("filter-param")) base.filter_params = expand(args.get_or("filter-param", ""), {});
  base.calibration_moves = args.has("calibration-moves");
  base.warmup = args.has("warmup");
  if (args.has("ideal")) base.sensor = sim::SensorModelParams::ideal();
  if (args.has("sensor-errors")) {
    std::string bad;
    base.sensor = only_errors(args.get_or("sensor-errors", ""), bad);
    if (!bad.empty()) {
      std::fprintf(stderr, "mocap bench accuracy: unknown sensor error group '%s'\n", bad.c_str());
      return 2;
    }
  }
  const auto motions = expand(args.get_or("motion", "all"), all_motions);
  const auto disturbances =
      expand(args.get_or("disturbance", "none,both"), {"none", "magnet", "desk", "both"});

  nlohmann::json out;
  out["bench"] = "accuracy";
  out["seed"] = seed;
  out["rate_hz"] = base.rate_hz;
  out["sensor_model"] = args.has("ideal") ? "ideal" : "consumer_mems_default";
  out["targets"] = {{"hinge_rmse_deg", kHingeTargetDeg},
                    {"three_dof_rmse_deg", kThreeDofTargetDeg},
                    {"root_drift_fraction", kRootDriftTarget}};
  if (args.has("markdown")) {
    std::fprintf(stderr,
                 "| motion | disturbance | elbow/knee max RMSE (deg) | 3-DOF max RMSE (deg) | "
                 "neck (inferred) max RMSE (deg) | segment mean RMSE (deg) | root drift |\n"
                 "|---|---|---|---|---|---|---|\n");
  }
  bool all_ok = true;
  try {
    for (const auto& m : motions) {
      for (const auto& d : disturbances) {
        sim::AccuracyOptions o = base;
        o.motion = m;
        o.disturbance = d;
        const sim::AccuracyResult r = sim::run_accuracy(o);
        out["results"].push_back(to_json(r));
        if (args.has("markdown")) print_markdown_row(r);
        all_ok = all_ok && r.calibrated;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap bench accuracy: %s\n", e.what());
    return 2;
  }
  std::printf("%s\n", out.dump(2).c_str());
  return all_ok ? 0 : 1;
}

}  // namespace mocap::bench
