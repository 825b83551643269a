// mocap score: the full-body metric of ../shared/datasets/cmu/README.md for a pose CSV (from
// `mocap replay --csv` or `mocap export --csv`) against a truth CSV (`mocap perform --truth`):
// each pose frame is paired with the truth frame at its time, scoring starts at --from seconds
// (the reference instant, just after calibration), and every segment present in both files
// with a sensor-like motion is scored (--segments to choose). Prints JSON.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/segments.hpp"
#include "mocap/sim/segment_metric.hpp"

namespace mocap::cmd {
namespace {

constexpr const char* kScoreUsage =
    "Both files: t,segment,w,x,y,z[,px,py,pz] (replay --csv, export --csv, perform --truth).";

/// Frames keyed by time in ns: each holds the orientations of the segments seen at that time.
struct ScoreFrames {
  std::map<int64_t, std::array<Eigen::Quaterniond, kSegmentCount>> at;
  std::map<int64_t, std::array<bool, kSegmentCount>> have;
};

bool read_score_frames(const std::string& path, ScoreFrames& out, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == 't' || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string f[6];
    for (auto& x : f)
      if (!std::getline(ss, x, ',')) {
        error = path + ":" + std::to_string(n) + ": expected t,segment,w,x,y,z";
        return false;
      }
    const auto seg = segment_from_name(f[1]);
    if (!seg) {
      error = path + ":" + std::to_string(n) + ": unknown segment '" + f[1] + "'";
      return false;
    }
    double v[5];
    try {
      for (int k = 0; k < 5; ++k)
        v[k] = std::stod(f[k == 0 ? 0 : k + 1]);
    } catch (const std::exception&) {
      error = path + ":" + std::to_string(n) + ": not numbers: " + line;
      return false;
    }
    const Eigen::Quaterniond q(v[1], v[2], v[3], v[4]);
    if (!q.coeffs().allFinite() || std::abs(q.norm() - 1) > 0.01) {
      error = path + ":" + std::to_string(n) + ": w,x,y,z is not a unit quaternion (a pose file?)";
      return false;
    }
    const int64_t t_ns = std::llround(v[0] * 1e9);
    out.at[t_ns][index(*seg)] = q.normalized();
    out.have[t_ns][index(*seg)] = true;
  }
  return true;
}

/// mocap score's command line (declared in add_score).
struct ScoreOptions {
  std::string poses, truth, segments;
  double from_s = -1e300;  ///< default: the pose file's first frame
};

int run_score(const ScoreOptions& o) {
  const double from_s = o.from_s;
  std::array<bool, kSegmentCount> scored{};
  if (!o.segments.empty()) {
    std::stringstream ss(o.segments);
    std::string name;
    while (std::getline(ss, name, ',')) {
      const auto seg = segment_from_name(name);
      if (!seg) {
        std::fprintf(stderr, "mocap score: unknown segment '%s'\n", name.c_str());
        return 2;
      }
      scored[index(*seg)] = true;
    }
  } else {
    scored.fill(true);
    scored[index(Segment::neck)] = false;
  }
  ScoreFrames poses, truth;
  std::string error;
  if (!read_score_frames(o.poses, poses, error) || !read_score_frames(o.truth, truth, error)) {
    std::fprintf(stderr, "mocap score: %s\n", error.c_str());
    return 1;
  }
  sim::SegmentMetric metric(scored);
  int unmatched = 0;
  const int64_t from_ns = from_s > -1e299 ? std::llround(from_s * 1e9) : INT64_MIN;
  for (const auto& [t, q] : poses.at) {
    if (t < from_ns) continue;
    // The truth frame at the pose's time (within half a millisecond).
    auto it = truth.at.lower_bound(t - 500'000);
    if (it == truth.at.end() || std::llabs(it->first - t) > 500'000) {
      ++unmatched;
      continue;
    }
    const auto& have_p = poses.have[t];
    const auto& have_t = truth.have[it->first];
    bool complete = true;
    for (int s = 0; s < kSegmentCount; ++s)
      complete = complete && (!scored[s] || (have_p[s] && have_t[s]));
    if (!complete) {
      ++unmatched;
      continue;
    }
    metric.add(q, it->second);
  }
  if (metric.frames() == 0) {
    std::fprintf(stderr, "mocap score: no pose frame has a truth frame at its time\n");
    return 1;
  }
  const sim::SegmentMetric::Result r = metric.result();
  nlohmann::json j;
  j["frames"] = r.frames;
  j["frames_without_truth"] = unmatched;
  j["mean_segment_error_deg"] = r.mean_deg;
  for (int s = 0; s < kSegmentCount; ++s)
    if (scored[s]) j["segment_error_deg"][std::string(kSegmentNames[s])] = r.segment_rms_deg[s];
  std::printf("%s\n", j.dump(2).c_str());
  return 0;
}

}  // namespace

void add_score(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ScoreOptions>();
  CLI::App* c = cli::add_command(
      app, "score", "full-body metric of a pose CSV against a truth CSV (datasets/cmu/README.md)");
  c->footer(kScoreUsage);
  c->add_option("POSES", o->poses, "pose CSV (replay --csv, export --csv)")->required();
  c->add_option("TRUTH", o->truth, "truth CSV (perform --truth)")->required();
  c->add_option("--from", o->from_s,
                "reference instant, seconds of the pose file (default: its first frame)")
      ->default_str("");
  c->add_option("--segments", o->segments,
                "comma list of segments to score (default: the 15 segments with standard sensor "
                "sites, all but the neck)");
  c->callback([o, &exit_code] { exit_code = run_score(*o); });
}

}  // namespace mocap::cmd
