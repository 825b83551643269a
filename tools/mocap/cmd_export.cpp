// mocap export: converts the poses recorded in a session file (docs/session-format.md) to CSV
// (t,segment,w,x,y,z,px,py,pz: one row per segment per frame), pose JSON lines (the stream's
// schema, docs/streaming.md, with the recorded wall-clock time), BVH (the skeleton's BvhWriter,
// body height from the recorded configuration), binary glTF (GltfWriter) or an OpenSense
// orientations table (OpenSimWriter). Damaged ranges are skipped and reported (exit status 3),
// a torn tail is reported; everything intact is exported.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/outputs/pose_json.hpp"
#include "mocap/session/session_reader.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/dropout_bridge.hpp"
#include "mocap/skeleton/gltf.hpp"
#include "mocap/skeleton/interpolation.hpp"
#include "mocap/skeleton/opensim.hpp"
#include "run_summary.hpp"

namespace mocap::cmd {
namespace {

constexpr const char* kExportUsage =
    "Converts the poses recorded in SESSION. CSV columns: t (seconds since the recording\n"
    "started), segment, w, x, y, z (q_earth_segment), px, py, pz (p_earth_segment_m, metres).\n"
    "JSON: one line per frame exactly as the pose stream sends it (docs/streaming.md), frames\n"
    "and times as recorded, t_unix_ns the recorded wall-clock time (the Blender add-on's import).\n"
    "BVH: N-pose rest, centimetres, the recorded body. glTF: binary .glb, one node per segment\n"
    "named like the BVH bones, a skin, one animation (rotations, root translation), metres.\n"
    "OpenSim: an OpenSense orientations table (pelvis_imu, femur_r_imu, ...: w,x,y,z in\n"
    "OpenSim's y-up ground frame). BVH, glTF and OpenSim are resampled to one fixed frame time\n"
    "(the recorded pipeline rate or --frame-rate). A sensor's dropout of up to 0.5 s is\n"
    "bridged (its segment slerped across the gap).\n"
    "A damaged session is read around the damage: every intact block is exported and each\n"
    "damaged range is reported (bytes, time span).\n"
    "Exit status: 0 exported (a torn tail after a crash is reported, not an error); 1 error;\n"
    "2 usage; 3 exported, but damaged data was skipped.\n";

/// Exit status of `mocap export` when damaged data was skipped (everything intact exported).
constexpr int kExitDamaged = 3;

/// Tells the user how reading ended when it did not end cleanly: the header recovered from its
/// copy, each damaged range skipped (bytes and time span since the recording's start), a torn
/// tail. Returns true if data was lost to damage.
bool report_tail(const SessionReader& r, const std::string& path) {
  using End = SessionReader::End;
  if (r.header_recovered())
    std::fprintf(stderr, "mocap export: %s: header damaged (%s); read from its copy\n",
                 path.c_str(), r.header_damage().c_str());
  const int64_t t0 = r.header().t_start_host_ns;
  const auto secs = [t0](int64_t t) -> std::string {
    if (t < 0) return "?";
    char b[32];
    std::snprintf(b, sizeof b, "%.3f s", static_cast<double>(t - t0) * 1e-9);
    return b;
  };
  for (const auto& d : r.damaged()) {
    // Blocks of different streams interleave: show the span in time order.
    const int64_t lo = d.t_after_ns < 0 ? d.t_before_ns : std::min(d.t_before_ns, d.t_after_ns);
    const int64_t hi = d.t_after_ns < 0 ? -1 : std::max(d.t_before_ns, d.t_after_ns);
    std::fprintf(stderr,
                 "mocap export: %s: damaged bytes %llu-%llu (%llu bytes, between %s and %s of "
                 "the recording) skipped: %s\n",
                 path.c_str(), static_cast<unsigned long long>(d.begin),
                 static_cast<unsigned long long>(d.end),
                 static_cast<unsigned long long>(d.end - d.begin), secs(lo).c_str(),
                 hi < 0 ? "the end" : secs(hi).c_str(), d.reason.c_str());
  }
  if (r.end() != End::clean && r.ignored_bytes() > 0 && r.damaged().empty())
    std::fprintf(stderr,
                 "mocap export: %s: %s; the last %llu bytes (an unfinished write) were "
                 "ignored\n",
                 path.c_str(), r.tail_reason().c_str(),
                 static_cast<unsigned long long>(r.ignored_bytes()));
  else if (r.end() != End::clean && r.ignored_bytes() > 0 &&
           r.damaged().back().begin != r.tail_offset())
    std::fprintf(stderr, "mocap export: %s: %s; the last %llu bytes were ignored\n", path.c_str(),
                 r.tail_reason().c_str(), static_cast<unsigned long long>(r.ignored_bytes()));
  if (!r.damaged().empty())
    std::fprintf(stderr,
                 "mocap export: %s: %zu damaged range%s (%llu bytes) skipped; everything intact "
                 "was exported (exit status %d)\n",
                 path.c_str(), r.damaged().size(), r.damaged().size() == 1 ? "" : "s",
                 static_cast<unsigned long long>(r.damaged_bytes()), kExitDamaged);
  return r.end() == End::corrupt;
}

/// The configuration recorded in the session (body model, pipeline rate), or the defaults.
daemon::Config recorded_config(const SessionReader& r, const std::string& in) {
  daemon::ConfigErrors errors;
  const auto cfg =
      daemon::parse_config(r.header().config_text, in + " (recorded config)", {}, errors);
  if (cfg) return *cfg;
  const daemon::Config fallback;
  std::fprintf(stderr,
               "mocap export: warning: the recorded configuration does not parse (%s); using "
               "body height %.2f m\n",
               errors.errors.empty() ? "empty" : errors.errors.front().to_string().c_str(),
               fallback.body.model.height_m);
  return fallback;
}

/// The session's poses, dropouts bridged (DropoutBridge), resampled to rate_hz if > 0.
class FinishedPoses {
 public:
  FinishedPoses(const BodyDimensions& dims, double rate_hz) : bridge_(dims) {
    if (rate_hz > 0) resampler_.emplace(rate_hz);
  }
  /// Calls emit(frame) for every pose of the session, in order.
  template <typename Emit>
  void run(SessionReader& r, Emit&& emit) {
    SessionReader::Block b;
    PoseFrame f;
    const auto drain = [&] {
      while (bridge_.next(f)) {
        if (t_first_ns_ < 0) t_first_ns_ = f.t_ns;
        t_last_ns_ = f.t_ns;
        if (!resampler_) {
          emit(f);
          continue;
        }
        resampler_->push(f);
        PoseFrame g;
        while (resampler_->next(g))
          emit(g);
      }
    };
    while (r.next(b)) {
      if (b.type != session::BlockType::pose) continue;
      bridge_.push(b.pose);
      drain();
    }
    bridge_.finish();
    drain();
  }
  long bridged() const { return bridge_.bridged(); }
  /// Time from the first to the last pose of the session, seconds.
  double duration_s() const {
    return t_last_ns_ > t_first_ns_ ? (t_last_ns_ - t_first_ns_) * 1e-9 : 0;
  }

 private:
  DropoutBridge bridge_;
  std::optional<PoseResampler> resampler_;
  int64_t t_first_ns_ = -1, t_last_ns_ = -1;
};

bool write_csv_row(std::FILE* f, double t, int s, const PoseFrame& p) {
  const auto& q = p.q_earth_segment[s];
  const auto& x = p.p_earth_segment_m[s];
  return std::fprintf(f, "%.6f,%.*s,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f\n", t,
                      static_cast<int>(kSegmentNames[s].size()), kSegmentNames[s].data(), q[0],
                      q[1], q[2], q[3], x[0], x[1], x[2]) > 0;
}

enum class Format { csv, json, bvh, gltf, opensim };

/// Writes every pose of the session as a pose-stream JSON line (format_pose_json) with its
/// wall-clock time from the session's clock (header, then clock blocks). Throws on a write
/// error.
long write_json_lines(SessionReader& r, FinishedPoses& poses, const std::string& out) {
  std::FILE* f = std::fopen(out.c_str(), "w");
  if (!f) throw std::runtime_error("cannot create '" + out + "': " + std::strerror(errno));
  std::vector<char> line(outputs::kPoseJsonMaxLine);
  long frames = 0;
  bool ok = true;
  poses.run(r, [&](const PoseFrame& p) {
    PoseFrame g = p;
    // The offset in force when the reader reached this pose (bridging delays a pose by at
    // most 0.5 s; the clock offset moves by microseconds over that).
    g.t_unix_ns = p.t_ns + r.unix_offset_ns();
    const std::size_t n = outputs::format_pose_json(g, line.data(), line.size());
    ok = n > 0 && std::fwrite(line.data(), 1, n, f) == n && ok;
    ++frames;
  });
  ok = !std::ferror(f) && ok;
  if (std::fclose(f) != 0 || !ok)
    throw std::runtime_error("writing '" + out + "' failed: " + std::strerror(errno));
  return frames;
}

int export_poses(SessionReader& r, const std::string& in, const std::string& out, Format format,
                 double rate_hz) {
  const daemon::Config cfg = recorded_config(r, in);
  const BodyModel body(cfg.body.model);
  // BVH, glTF and OpenSim have one fixed frame time: resample to the recorded pipeline rate
  // unless told otherwise.
  const bool fixed_rate = format != Format::csv && format != Format::json;
  if (fixed_rate && rate_hz <= 0) rate_hz = cfg.pipeline.rate_hz;
  FinishedPoses poses(body.dimensions(), rate_hz);
  long frames = 0;
  // Every finished frame into one of the motion writers, then close it.
  const auto write_all = [&](auto& writer) {
    poses.run(r, [&](const PoseFrame& f) {
      writer.write_frame(f);
      ++frames;
    });
    writer.close();
  };
  try {
    if (format == Format::json) {
      frames = write_json_lines(r, poses, out);
    } else if (format == Format::gltf) {
      GltfWriterOptions opt;
      opt.frame_time_s = 1.0 / rate_hz;
      GltfWriter writer(out, body, opt);
      write_all(writer);
    } else if (format == Format::opensim) {
      OpenSimWriter writer(out, {.rate_hz = rate_hz});
      write_all(writer);
    } else if (format == Format::bvh) {
      BvhWriterOptions opt;
      opt.frame_time_s = 1.0 / rate_hz;
      BvhWriter writer(out, body, opt);
      write_all(writer);
    } else {
      std::FILE* f = std::fopen(out.c_str(), "w");
      if (!f) throw std::runtime_error("cannot create '" + out + "': " + std::strerror(errno));
      bool ok = std::fprintf(f, "t,segment,w,x,y,z,px,py,pz\n") > 0;
      const int64_t t0 = r.header().t_start_host_ns;
      poses.run(r, [&](const PoseFrame& p) {
        const double t = static_cast<double>(p.t_ns - t0) * 1e-9;
        for (int s = 0; s < kSegmentCount; ++s)
          ok = write_csv_row(f, t, s, p) && ok;
        ++frames;
      });
      ok = !std::ferror(f) && ok;
      if (std::fclose(f) != 0 || !ok)
        throw std::runtime_error("writing '" + out + "' failed: " + std::strerror(errno));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap export: %s\n", e.what());
    return 1;
  }
  const bool damaged = report_tail(r, in);
  if (frames == 0) {
    std::fprintf(stderr, "mocap export: %s holds no poses\n", in.c_str());
    return 1;
  }
  nlohmann::json extra = {{"body_height_m", std::round(body.dimensions().height_m * 100) / 100},
                          {"bridged_segment_frames", poses.bridged()},
                          {"damaged_ranges", r.damaged().size()}};
  if (rate_hz > 0) extra["rate_hz"] = rate_hz;
  print_run_summary("export", in, {out}, frames, poses.duration_s(), extra);
  return damaged ? kExitDamaged : 0;
}

}  // namespace

void add_export(CLI::App& app, int& exit_code) {
  struct ExportOptions {
    std::string input, csv, json, bvh, gltf, opensim;
    double rate_hz = 0;
  };
  auto o = std::make_shared<ExportOptions>();
  CLI::App* c = cli::add_command(
      app, "export", "convert a recorded session to CSV, pose JSON lines, BVH, glTF or OpenSim");
  c->footer(kExportUsage);
  c->add_option("SESSION", o->input, "the recorded session (.mocapses)")->required();
  CLI::Option* outs[] = {
      c->add_option("--csv", o->csv, "write the poses as CSV to this file (one output per run)"),
      c->add_option("--json", o->json,
                    "write the poses as pose-stream JSON lines to this file (one output per run)"),
      c->add_option("--bvh", o->bvh, "write the poses as BVH to this file (one output per run)"),
      c->add_option("--gltf", o->gltf,
                    "write the poses as binary glTF (.glb) to this file (one output per run)"),
      c->add_option(
          "--opensim", o->opensim,
          "write an OpenSense orientations table (.sto) to this file (one output per run)")};
  // One output per run: each writer reads the session once.
  for (CLI::Option* a : outs)
    for (CLI::Option* b : outs)
      if (a != b) a->excludes(b);
  CLI::Option* rate =
      c->add_option(
           "--frame-rate", o->rate_hz,
           "resample to this frame rate, Hz (default: CSV and JSON as recorded, the others at "
           "the recorded pipeline rate)")
          ->check(CLI::Range(1e-9, 10000.0))
          ->default_str("");
  // --rate means a sensor's sample rate elsewhere (perform, simulate, bench).
  cli::add_deprecated_alias(*c, "--rate", o->rate_hz, rate)->check(CLI::Range(1e-9, 10000.0));
  c->callback([o, &exit_code] {
    if (o->csv.empty() && o->json.empty() && o->bvh.empty() && o->gltf.empty() &&
        o->opensim.empty()) {
      std::fprintf(stderr,
                   "mocap export: give one output: --csv, --json, --bvh, --gltf or --opensim\n");
      exit_code = 2;
      return;
    }
    SessionReader reader;
    std::string error;
    if (!reader.open(o->input, &error)) {
      std::fprintf(stderr, "mocap export: %s\n", error.c_str());
      exit_code = 1;
      return;
    }
    const auto [out, format] = !o->csv.empty()       ? std::pair{o->csv, Format::csv}
                               : !o->json.empty()    ? std::pair{o->json, Format::json}
                               : !o->gltf.empty()    ? std::pair{o->gltf, Format::gltf}
                               : !o->opensim.empty() ? std::pair{o->opensim, Format::opensim}
                                                     : std::pair{o->bvh, Format::bvh};
    exit_code = export_poses(reader, o->input, out, format, o->rate_hz);
  });
}

}  // namespace mocap::cmd
