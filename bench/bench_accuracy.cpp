// mocap bench accuracy: the virtual performer (built-in motions, or real CMU clips with --clips)
// through the body tracker (rig::BodyTracker, as mocapd runs it) and through each sensor's
// filter alone, 9D or 6D, with and without magnetic disturbances, over seeds. Prints JSON (the
// dataset README's full-body metric for both, per segment; joint-angle RMSE, root drift) and,
// with --markdown, a table on stderr (scripts/accuracy-report builds docs/accuracy.md's).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bench.hpp"
#include "mocap/core/cli.hpp"
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
  if (r.dropout_joint_after_deg >= 0) {
    j["dropout_joint_before_deg"] = r.dropout_joint_before_deg;
    j["dropout_joint_after_deg"] = r.dropout_joint_after_deg;
  }
  j["segment_rmse_deg"] = segments;
  j["hinge_max_rmse_deg"] = r.hinge_max_rmse_deg;
  j["three_dof_max_rmse_deg"] = r.three_dof_max_rmse_deg;
  j["inferred_neck_max_rmse_deg"] = r.inferred_max_rmse_deg;
  j["segment_mean_rmse_deg"] = r.segment_mean_rmse_deg;
  j["metric_mean_deg"] = r.metric_mean_deg;
  j["alone_mean_deg"] = r.alone_mean_deg;
  {
    nlohmann::json m, a;
    double worst = -1e9, worst_same_g = -1e9;
    for (int s = 0; s < kSegmentCount; ++s) {
      if (r.alone_segment_deg[s] == 0 && r.metric_segment_deg[s] == 0) continue;
      m[std::string(kSegmentNames[s])] = r.metric_segment_deg[s];
      a[std::string(kSegmentNames[s])] = r.alone_segment_deg[s];
      worst = std::max(worst, r.metric_segment_deg[s] - r.alone_segment_deg[s]);
      worst_same_g =
          std::max(worst_same_g, r.metric_segment_alone_g_deg[s] - r.alone_segment_deg[s]);
    }
    j["metric_segment_deg"] = m;
    j["alone_segment_deg"] = a;
    j["worst_segment_excess_deg"] = worst;
    j["worst_segment_excess_same_g_deg"] = worst_same_g;
    double jump = 0;
    for (int s = 0; s < kSegmentCount; ++s)
      jump = std::max(jump, r.max_jump_deg[s]);
    j["max_jump_deg"] = jump;
  }
  nlohmann::json diag;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (r.sensor_inclination_rmse_deg[s] == 0 && r.sensor_heading_drift_deg[s] == 0) continue;
    diag[std::string(kSegmentNames[s])] = {
        {"mount_yaw_error_deg", r.mount_yaw_error_deg[s]},
        {"pose_deviation_deg", r.pose_deviation_deg[s]},
        {"filter_heading_drift_deg", r.sensor_heading_drift_deg[s]},
        {"filter_inclination_rmse_deg", r.sensor_inclination_rmse_deg[s]},
        {"mag_disturbed_fraction", r.sensor_mag_disturbed_fraction[s]}};
  }
  j["sensor_diagnostics"] = diag;
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
  double worst = 0;
  for (int s = 0; s < kSegmentCount; ++s)
    worst = std::max(worst, r.metric_segment_deg[s] - r.alone_segment_deg[s]);
  std::fprintf(stderr, "| %s | %s | %.2f | %.2f | %+.2f | %.2f | %.2f | %s |\n", r.motion.c_str(),
               r.disturbance.c_str(), r.metric_mean_deg, r.alone_mean_deg, worst,
               r.hinge_max_rmse_deg, r.three_dof_max_rmse_deg, drift);
}

/// mocap bench accuracy's command line (declared in add_accuracy).
struct AccuracyCommandOptions {
  std::string motion = "all", disturbance = "none,both", heading = "normals", mag = "on", clips,
              seeds, filter_param, sensor_errors, mount = "sites", mounting_motion = "on", dropout,
              rig = "full";
  long seed = 1;
  double rate_hz = 100, frame_rate_hz = 0, score_after_s = 0, session_s = 0;
  bool calibration_moves = false, gyro_scale_calibration = false, warmup = false, ideal = false,
       markdown = false, fused_on_device = false;
};

int run_accuracy(const AccuracyCommandOptions& args) {
  std::vector<std::string> all_motions;
  for (auto n : sim::motion_names())
    if (n != "npose") all_motions.emplace_back(n);
  sim::AccuracyOptions base;
  const long seed = args.seed;
  base.rate_hz = args.rate_hz;
  base.seed = static_cast<uint64_t>(seed);
  const std::string& heading = args.heading;
  if (heading == "normals")
    base.heading = HeadingSource::mount_normals;
  else if (heading == "pelvis")
    base.heading = HeadingSource::pelvis_sensor;
  else if (heading == "mean")
    base.heading = HeadingSource::mean_sensors;
  else
    base.heading = HeadingSource::explicit_heading;  // truth
  if (args.gyro_scale_calibration) base.gyro_scale_calibration = true;
  if (!args.filter_param.empty()) base.filter_params = expand(args.filter_param, {});
  base.calibration_moves = args.calibration_moves;
  base.use_mag = args.mag == "on";
  base.frame_rate_hz = args.frame_rate_hz;

  base.warmup = args.warmup;
  base.mounting_motion = args.mounting_motion == "on";
  if (!args.dropout.empty()) {
    // SEGMENT:START:SECONDS (SEGMENT "all": every sensor)
    const auto a = args.dropout.find(':'), b = args.dropout.rfind(':');
    const std::string name = args.dropout.substr(0, a);
    const bool all = name == "all";
    const auto seg = segment_from_name(name);
    char* end = nullptr;
    if (a != std::string::npos && b != a) {
      base.dropout_start_s = std::strtod(args.dropout.c_str() + a + 1, &end);
      if (end == args.dropout.c_str() + b)
        base.dropout_s = std::strtod(args.dropout.c_str() + b + 1, &end);
    }
    if ((!all && !seg) || b == a || *end != 0 || base.dropout_start_s < 0 || base.dropout_s <= 0) {
      std::fprintf(stderr,
                   "mocap bench accuracy: --dropout '%s': expected SEGMENT:START_S:SECONDS (e.g. "
                   "forearm_l:5:3, or all:5:3)\n",
                   args.dropout.c_str());
      return 2;
    }
    base.dropout_segment = all ? sim::AccuracyOptions::kDropoutAll : index(*seg);
  }
  base.fused_on_device = args.fused_on_device;
  base.score_after_s = args.score_after_s;
  base.session_s = args.session_s;
  base.rig =
      args.rig == "lower" ? sim::AccuracyOptions::Rig::lower_body : sim::AccuracyOptions::Rig::full;
  if (args.ideal) base.sensor = sim::SensorModelParams::ideal();
  if (!args.sensor_errors.empty()) {
    std::string bad;
    base.sensor = only_errors(args.sensor_errors, bad);
    if (!bad.empty()) {
      std::fprintf(stderr, "mocap bench accuracy: unknown sensor error group '%s'\n", bad.c_str());
      return 2;
    }
  }
  base.sensor.random_mount_orientation = args.mount == "random";
  auto motions = expand(args.motion, all_motions);
  if (!args.clips.empty()) {
    motions.clear();
    std::vector<std::string> files;
    for (const auto& e : std::filesystem::directory_iterator(args.clips))
      if (e.path().extension() == ".bvh") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    for (const auto& f : files)
      motions.push_back(f);
    base.calibration_moves = true;
  }
  std::vector<uint64_t> seeds;
  for (const std::string& v : expand(args.seeds.empty() ? std::to_string(seed) : args.seeds, {}))
    seeds.push_back(std::strtoull(v.c_str(), nullptr, 10));
  const auto disturbances =
      expand(args.disturbance, {"none", "magnet", "desk", "both", "arm_magnet"});

  nlohmann::json out;
  out["bench"] = "accuracy";
  out["seed"] = seed;
  out["rate_hz"] = base.rate_hz;
  out["sensor_model"] = args.ideal ? "ideal" : "consumer_mems_default";
  out["targets"] = {{"hinge_rmse_deg", kHingeTargetDeg},
                    {"three_dof_rmse_deg", kThreeDofTargetDeg},
                    {"root_drift_fraction", kRootDriftTarget}};
  if (args.markdown) {
    std::fprintf(stderr,
                 "| motion | disturbance | tracker (deg) | filters alone (deg) | worst segment "
                 "excess (deg) | elbow/knee max RMSE (deg) | 3-DOF max RMSE (deg) | root drift |\n"
                 "|---|---|---|---|---|---|---|---|\n");
  }
  bool all_ok = true;
  try {
    for (const auto& m : motions) {
      for (const auto& d : disturbances)
        for (const uint64_t sd : seeds) {
          sim::AccuracyOptions o = base;
          o.motion = m;
          o.disturbance = d;
          o.seed = sd;
          const sim::AccuracyResult r = sim::run_accuracy(o);
          nlohmann::json jr = to_json(r);
          jr["seed"] = sd;
          out["results"].push_back(jr);
          if (args.markdown) print_markdown_row(r);
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

}  // namespace

void add_accuracy(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<AccuracyCommandOptions>();
  CLI::App* c = cli::add_command(bench, "accuracy",
                                 "the virtual performer through the pipeline, scored per segment");
  c->add_option("--motion", o->motion, "motion name, comma list or 'all'");
  c->add_option("--disturbance", o->disturbance,
                "none|magnet|desk|both|arm_magnet, comma list or 'all'");
  c->add_option("--seed", o->seed, "random seed")->check(CLI::NonNegativeNumber);
  c->add_option("--seeds", o->seeds, "comma list of seeds (default: --seed)");
  c->add_option("--rate", o->rate_hz, "sensor rate, Hz")->check(CLI::PositiveNumber);
  c->add_option("--heading", o->heading, "calibration heading source (normals: as the daemon)")
      ->check(CLI::IsMember({"normals", "pelvis", "mean", "truth"}));
  c->add_flag("--calibration-moves", o->calibration_moves,
              "calibrate with N-pose + calibration moves (knee bends, elbow curls) before each "
              "motion");
  c->add_flag("--gyro-scale-calibration", o->gyro_scale_calibration,
              "calibrate each sensor's gyro scale first (table spins, as a user does once per "
              "sensor) and divide it out");
  c->add_flag("--warmup", o->warmup,
              "the sensors run for 22 s of walking and turning before the calibration stand");
  c->add_option("--mag", o->mag, "with magnetometers (9D): on|off (off: 6D)")
      ->check(CLI::IsMember({"on", "off"}));
  c->add_option("--frame-rate", o->frame_rate_hz, "pose frames per second (0: one per sample time)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--clips", o->clips,
                "every .bvh file in this folder as a motion (calibration procedure first)")
      ->check(CLI::ExistingDirectory);
  c->add_option("--filter-param", o->filter_param,
                "AttitudeFilter overrides, comma list of name=value");
  c->add_option("--sensor-errors", o->sensor_errors,
                "only these consumer-MEMS error groups, comma list of mount,mag,gyr,acc,timing "
                "(mag = mag_hard_iron + mag_scale + mag_noise; error breakdown; default all)");
  c->add_flag("--ideal", o->ideal,
              "ideal sensors (no noise, bias, misalignment): isolates the pipeline");
  c->add_option(
       "--mount", o->mount,
       "sites: sensors on the standard sites (5 deg strap tilt); random: each strapped at a "
       "uniformly random orientation on its segment (the rig still assumes the sites)")
      ->check(CLI::IsMember({"sites", "random"}));
  c->add_option("--mounting-motion", o->mounting_motion,
                "on: the calibration moves also serve as the mounting motion (facings from the "
                "segments' tilt, as `mocapctl calibrate mounting`); off: N-pose only")
      ->check(CLI::IsMember({"on", "off"}));
  c->add_option("--dropout", o->dropout,
                "SEGMENT:START_S:SECONDS: that segment's sensor sends nothing for SECONDS from "
                "START_S into the evaluated motion (a radio drop, a tracker rebooting); "
                "SEGMENT all: every sensor (the receiver or the network dropped)");
  c->add_flag("--fused-on-device", o->fused_on_device,
              "the sensors compute their orientation themselves (SlimeVR over UDP): a dropout "
              "drops only the link, their fusion runs on through it");
  c->add_option("--rig", o->rig,
                "full: every sensor on the body; lower: the lower body's seven (pelvis, thighs, "
                "shanks, feet; the others unused and unscored)")
      ->check(CLI::IsMember({"full", "lower"}));
  c->add_option("--score-after", o->score_after_s,
                "seconds into the motion (after the calibration procedure) the scoring and the "
                "metric's reference instant start; the tracker runs from the calibration on")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--session", o->session_s,
                "seconds: each BVH clip played back and forth until the motion lasts this long (a "
                "long session; with --score-after, its end scored alone)")
      ->check(CLI::PositiveNumber);
  c->add_flag("--markdown", o->markdown, "also print a markdown table on stderr");
  c->callback([o, &exit_code] { exit_code = run_accuracy(*o); });
}

}  // namespace mocap::bench
