// mocap export: converts the poses recorded in a session file (docs/session-format.md) to CSV
// (t,segment,w,x,y,z,px,py,pz: one row per segment per frame) or BVH (the skeleton's BvhWriter,
// body height from the recorded configuration). A torn or corrupt tail is reported and
// everything before it is exported.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/session/session_reader.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap::cmd {
namespace {

constexpr const char* kExportUsage =
    "usage: mocap export SESSION (--csv OUT.csv | --bvh OUT.bvh)\n"
    "Converts the poses recorded in SESSION. CSV columns: t (seconds since the recording\n"
    "started), segment, w, x, y, z (q_earth_segment), px, py, pz (p_earth_segment_m, metres).\n"
    "BVH: N-pose rest, centimetres, the session's mean frame interval, the recorded body height.\n";

/// Tells the user how reading ended when it did not end cleanly.
void report_tail(const SessionReader& r, const std::string& path) {
  using End = SessionReader::End;
  if (r.end() == End::torn)
    std::fprintf(stderr,
                 "mocap export: %s: %s; the last %llu bytes (an unfinished write) were "
                 "ignored\n",
                 path.c_str(), r.tail_reason().c_str(),
                 static_cast<unsigned long long>(r.ignored_bytes()));
  else if (r.end() == End::corrupt)
    std::fprintf(stderr, "mocap export: %s: damaged: %s; %llu bytes after it were not read\n",
                 path.c_str(), r.tail_reason().c_str(),
                 static_cast<unsigned long long>(r.ignored_bytes()));
}

int export_csv(SessionReader& r, const std::string& in, const std::string& out) {
  std::FILE* f = std::fopen(out.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "mocap export: cannot create '%s': %s\n", out.c_str(),
                 std::strerror(errno));
    return 1;
  }
  std::fprintf(f, "t,segment,w,x,y,z,px,py,pz\n");
  const int64_t t0 = r.header().t_start_host_ns;
  SessionReader::Block b;
  long frames = 0;
  while (r.next(b)) {
    if (b.type != session::BlockType::pose) continue;
    const double t = static_cast<double>(b.pose.t_ns - t0) * 1e-9;
    for (int s = 0; s < kSegmentCount; ++s) {
      const auto& q = b.pose.q_earth_segment[s];
      const auto& p = b.pose.p_earth_segment_m[s];
      std::fprintf(f, "%.6f,%.*s,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f\n", t,
                   static_cast<int>(kSegmentNames[s].size()), kSegmentNames[s].data(), q[0], q[1],
                   q[2], q[3], p[0], p[1], p[2]);
    }
    ++frames;
  }
  const bool write_ok = !std::ferror(f);
  if (std::fclose(f) != 0 || !write_ok) {
    std::fprintf(stderr, "mocap export: writing '%s' failed: %s\n", out.c_str(),
                 std::strerror(errno));
    return 1;
  }
  report_tail(r, in);
  if (frames == 0) {
    std::fprintf(stderr, "mocap export: %s holds no poses\n", in.c_str());
    return 1;
  }
  std::fprintf(stderr, "mocap export: %ld frames -> %s\n", frames, out.c_str());
  return 0;
}

/// Body height from the configuration recorded in the session (the one the poses were
/// computed with); the default height, with a warning, if it does not parse.
/// The body model of the recorded configuration (height and segment offsets).
BodyModelConfig recorded_body(const SessionReader& r, const std::string& in) {
  daemon::ConfigErrors errors;
  const auto cfg =
      daemon::parse_config(r.header().config_text, in + " (recorded config)", {}, errors);
  if (cfg) return cfg->body.model;
  const BodyModelConfig fallback;
  std::fprintf(stderr,
               "mocap export: warning: the recorded configuration does not parse (%s); using "
               "body height %.2f m\n",
               errors.errors.empty() ? "empty" : errors.errors.front().to_string().c_str(),
               fallback.height_m);
  return fallback;
}

int export_bvh(SessionReader& r, const std::string& in, const std::string& out) {
  // First pass: frame count and mean frame interval (BVH has one fixed frame time).
  SessionReader::Block b;
  long frames = 0;
  int64_t t_first = 0, t_last = 0;
  while (r.next(b)) {
    if (b.type != session::BlockType::pose) continue;
    if (frames == 0) t_first = b.pose.t_ns;
    t_last = b.pose.t_ns;
    ++frames;
  }
  report_tail(r, in);
  if (frames == 0) {
    std::fprintf(stderr, "mocap export: %s holds no poses\n", in.c_str());
    return 1;
  }
  BvhWriterOptions opt;
  if (frames > 1 && t_last > t_first)
    opt.frame_time_s =
        static_cast<double>(t_last - t_first) * 1e-9 / static_cast<double>(frames - 1);
  const BodyModelConfig body = recorded_body(r, in);
  SessionReader again;
  std::string error;
  if (!again.open(in, &error)) {
    std::fprintf(stderr, "mocap export: %s\n", error.c_str());
    return 1;
  }
  try {
    BvhWriter writer(out, BodyModel(body), opt);
    while (again.next(b))
      if (b.type == session::BlockType::pose) writer.write_frame(b.pose);
    writer.close();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap export: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "mocap export: %ld frames (%.3f s each, body height %.2f m) -> %s\n", frames,
               opt.frame_time_s, body.height_m, out.c_str());
  return 0;
}

}  // namespace

int run_export(int argc, char** argv) {
  CliArgs args;
  args.option("csv", "write the poses as CSV to this file")
      .option("bvh", "write the poses as BVH to this file")
      .flag("help", "show this help");
  if (!args.parse(argc, argv, 1)) {
    std::fprintf(stderr, "mocap export: %s\n%s", args.error().c_str(), kExportUsage);
    return 2;
  }
  if (args.has("help")) {
    std::printf("%s%s", kExportUsage, args.help().c_str());
    return 0;
  }
  if (args.positional().size() != 1 || args.has("csv") == args.has("bvh")) {
    std::fprintf(stderr, "%s", kExportUsage);
    return 2;
  }
  const std::string in = args.positional()[0];
  SessionReader reader;
  std::string error;
  if (!reader.open(in, &error)) {
    std::fprintf(stderr, "mocap export: %s\n", error.c_str());
    return 1;
  }
  if (args.has("csv")) return export_csv(reader, in, *args.get("csv"));
  return export_bvh(reader, in, *args.get("bvh"));
}

}  // namespace mocap::cmd
