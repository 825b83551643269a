// mocap setup: assigns sensors to body segments by motion. Lists every sensor it can hear
// (tools/setup: the devices `mocap devices` finds, ports given with --port, SlimeVR boards on
// the network, each probed through the real drivers), asks the user to move one segment at a
// time, from the hands and feet inwards ("wave your left hand"), assigns the sensor that moved
// alone (MotionJudge), asks again when two moved at once, leaves out and names the sensors never
// moved, then writes the rig (rig_writer) and checks it as `mocapd --check-config` does.
// Prompts and results go to stdout one line each ("move SEGMENT: what to do", "assigned ...");
// answers come from stdin (a terminal or a script): an empty line (or "skip") skips a segment
// without a sensor, "undo" re-asks the last assignment, "quit" writes what is assigned so far.
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/setup/candidates.hpp"
#include "mocap/setup/listener.hpp"
#include "mocap/setup/motion_judge.hpp"
#include "mocap/setup/rig_writer.hpp"

namespace mocap::cmd {
namespace {

/// The prompts, in the order they are asked: hands and feet first, then inwards, so that the
/// segments an inner joint also moves already have their sensors.
struct Ask {
  Segment segment;
  const char* text;
};
constexpr Ask kAsks[] = {
    {Segment::hand_l, "wave your left hand (the wrist only, forearm still)"},
    {Segment::forearm_l, "bend and straighten your left elbow (upper arm still)"},
    {Segment::upper_arm_l, "raise your left arm sideways and lower it"},
    {Segment::hand_r, "wave your right hand (the wrist only, forearm still)"},
    {Segment::forearm_r, "bend and straighten your right elbow (upper arm still)"},
    {Segment::upper_arm_r, "raise your right arm sideways and lower it"},
    {Segment::foot_l, "tap your left toes (the ankle only)"},
    {Segment::shank_l, "swing your left lower leg: bend and straighten the knee (thigh still)"},
    {Segment::thigh_l, "lift your left knee"},
    {Segment::foot_r, "tap your right toes (the ankle only)"},
    {Segment::shank_r, "swing your right lower leg: bend and straighten the knee (thigh still)"},
    {Segment::thigh_r, "lift your right knee"},
    {Segment::head, "nod your head"},
    {Segment::neck, "bend your neck forward and back (shoulders still)"},
    {Segment::torso, "bend your upper body forward and back"},
    {Segment::pelvis, "turn your hips left and right"},
};

/// After this long without a decision the user is reminded of the answers.
constexpr auto kRemindAfter = std::chrono::seconds(8);

/// mocap setup's command line (declared in add_setup).
struct SetupOptions {
  std::string out = "rig.toml";
  bool force = false, no_scan = false;
  std::vector<std::string> ports;
  std::string slimevr = "0.0.0.0:6969", segments;
  double slimevr_listen_s = 2.0, probe_s = 1.5, window_s = 0.25, hold_s = 0.75;
  double threshold_dps = 60, dominance = 3, timeout_s = 0;
};

void say(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
void say(const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  std::vprintf(fmt, ap);
  va_end(ap);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

/// Lines typed on stdin, read without blocking (a closed stdin is simply never read again).
class Answers {
 public:
  /// The next whole line if one is there; false if none yet.
  bool next(std::string& line) {
    while (open_) {
      pollfd p{0, POLLIN, 0};
      if (::poll(&p, 1, 0) <= 0) break;
      char b[256];
      const ssize_t n = ::read(0, b, sizeof b);
      if (n <= 0) {
        open_ = false;
        break;
      }
      buf_.append(b, static_cast<std::size_t>(n));
    }
    const auto nl = buf_.find('\n');
    if (nl == std::string::npos) return false;
    line = buf_.substr(0, nl);
    buf_.erase(0, nl + 1);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' '))
      line.pop_back();
    return true;
  }

 private:
  std::string buf_;
  bool open_ = true;
};

std::string describe(const setup::MotionMeter::Seen& s, double rate_hz, const setup::Candidate& c) {
  std::string fields;
  if (s.fields & kFieldGyr) fields += "gyro";
  if (s.fields & kFieldAcc) fields += fields.empty() ? "acc" : "+acc";
  if (s.fields & kFieldMag) fields += fields.empty() ? "mag" : "+mag";
  if (!(s.fields & kFieldGyr) && (s.fields & kFieldQuat)) fields = "orientation";
  char b[64];
  std::snprintf(b, sizeof b, ", %.0f Hz", rate_hz);
  return c.sensor.driver + ": " + fields + b;
}

/// The segments to ask for, in kAsks order ("" = all). Throws on an unknown name.
std::vector<Ask> asks_for(const std::string& list) {
  std::vector<Ask> out;
  std::vector<bool> wanted(kSegmentCount, list.empty());
  std::stringstream ss(list);
  for (std::string name; std::getline(ss, name, ',');) {
    const auto seg = segment_from_name(name);
    if (!seg) throw std::invalid_argument("--segments: '" + name + "' is not a segment name");
    wanted[index(*seg)] = true;
  }
  for (const Ask& a : kAsks)
    if (wanted[index(a.segment)]) out.push_back(a);
  return out;
}

int run_setup(const SetupOptions& o) {
  std::vector<Ask> asks;
  try {
    asks = asks_for(o.segments);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "mocap setup: %s\n", e.what());
    return 2;
  }
  namespace fs = std::filesystem;
  if (fs::exists(o.out) && !o.force) {
    std::fprintf(stderr, "mocap setup: %s exists (--force replaces it)\n", o.out.c_str());
    return 1;
  }
  say("mocap setup: looking for sensors (serial, HID, USB%s)...",
      o.slimevr.empty() ? "" : (", SlimeVR on udp " + o.slimevr).c_str());
  setup::FindOptions fo;
  fo.scan = !o.no_scan;
  fo.ports = o.ports;
  fo.slimevr = o.slimevr;
  fo.slimevr_listen_s = o.slimevr_listen_s;
  std::vector<std::string> notes;
  auto found = setup::find_candidates(fo, notes);
  for (const auto& n : notes)
    say("note: %s", n.c_str());
  if (found.empty()) {
    say("no sensor found: plug one in, name its port with --port PATH, or switch SlimeVR "
        "trackers on (`mocap devices` lists what is connected)");
    return 1;
  }
  LogSink sink(stderr);
  setup::Listener listener(std::move(found), Logger(sink, "mocap setup", LogLevel::warn));
  listener.probe(o.probe_s, [](const std::string& m) { say("  %s", m.c_str()); });
  // Half a second more of listening: each sensor's rate, and late IMU slots of SlimeVR boards.
  listener.meter().take(monotonic_ns());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const auto rates = listener.meter().take(monotonic_ns());
  const auto& cands = listener.candidates();
  std::vector<int> label(cands.size(), 0);  // s1, s2, ... for the sensors heard
  int heard = 0;
  std::vector<std::string> left_out, silent;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    if (listener.heard(i)) label[i] = ++heard;
  }
  say("heard %d sensor%s:", heard, heard == 1 ? "" : "s");
  const auto name_of = [&](std::size_t i) {
    return "s" + std::to_string(label[i]) + " " + cands[i].what;
  };
  for (std::size_t i = 0; i < cands.size(); ++i) {
    if (label[i]) {
      say("  %s (%s)", name_of(i).c_str(),
          describe(listener.meter().seen(i), rates[i].rate_hz, cands[i]).c_str());
    } else if (!cands[i].optional) {
      std::string tried;
      for (const auto& p : cands[i].probes)
        tried += (tried.empty() ? "" : ", ") + p.driver +
                 (p.baud > 0 ? " at " + std::to_string(p.baud) + " baud" : "");
      say("  silent: %s (no samples as %s)", cands[i].what.c_str(), tried.c_str());
      silent.push_back(cands[i].what);
    }
  }
  if (heard == 0) {
    say("no sensor sends anything: nothing to assign");
    return 1;
  }
  say("Move each segment asked for, alone, for a second or two: the sensor that moves is "
      "assigned to it. Enter (or \"skip\"): this segment has no sensor; \"undo\": ask the last "
      "one again; \"quit\": write what is assigned.");

  setup::JudgeParams jp;
  jp.threshold_rad_s = o.threshold_dps * M_PI / 180.0;
  jp.dominance = o.dominance;
  jp.hold_windows = std::max(1, static_cast<int>(std::lround(o.hold_s / o.window_s)));
  setup::MotionJudge judge(jp);
  std::vector<int> segment_of(cands.size(), -1);  // assigned segment per candidate
  std::vector<bool> skipped(kSegmentCount, false);
  std::vector<std::pair<std::size_t, std::size_t>> history;  // (ask, candidate) assigned
  Answers answers;
  const auto window = std::chrono::duration<double>(o.window_s);
  bool quit = false;
  for (std::size_t k = 0; k < asks.size() && !quit;) {
    int free_heard = 0;
    for (std::size_t i = 0; i < cands.size(); ++i)
      free_heard += label[i] && segment_of[i] < 0;
    if (free_heard == 0) {
      say("every sensor heard is assigned");
      break;
    }
    const Ask& ask = asks[k];
    const std::string seg(name(ask.segment));
    skipped[index(ask.segment)] = false;
    judge.reset();
    say("move %s: %s", seg.c_str(), ask.text);
    listener.meter().take(monotonic_ns());  // what moved before the prompt does not count
    const auto started = std::chrono::steady_clock::now();
    auto next = started + window;
    bool settling = false;  // after "two at once": waiting for stillness before asking again
    bool reminded = false;
    std::size_t next_k = k + 1;
    for (;;) {
      std::this_thread::sleep_until(next);
      next += window;
      std::string line;
      if (answers.next(line)) {
        if (line.empty() || line == "s" || line == "skip") {
          say("skipped %s: no sensor on it", seg.c_str());
          skipped[index(ask.segment)] = true;
          break;
        }
        if (line == "u" || line == "undo") {
          if (history.empty()) {
            say("nothing to undo");
          } else {
            const auto [ask_k, cand] = history.back();
            history.pop_back();
            say("undone: %s is free again; asking for %s again", name_of(cand).c_str(),
                std::string(name(asks[ask_k].segment)).c_str());
            segment_of[cand] = -1;
            next_k = ask_k;
            break;
          }
        } else if (line == "q" || line == "quit") {
          quit = true;
          break;
        } else {
          say("answers: Enter or skip, undo, quit (not \"%s\")", line.c_str());
        }
      }
      const auto w = listener.meter().take(monotonic_ns());
      std::vector<double> speed(cands.size(), 0.0);
      std::vector<bool> free(cands.size(), false);
      for (std::size_t i = 0; i < cands.size(); ++i) {
        speed[i] = w[i].speed_rad_s;
        free[i] = label[i] && segment_of[i] < 0;
      }
      if (settling) {
        if (judge.still(speed, free)) {
          settling = false;
          judge.reset();
          say("move %s: %s", seg.c_str(), ask.text);
        }
        continue;
      }
      const auto v = judge.judge(speed, free);
      if (v == setup::MotionJudge::Verdict::assigned) {
        const auto i = static_cast<std::size_t>(judge.winner());
        segment_of[i] = index(ask.segment);
        history.emplace_back(k, i);
        say("assigned %s: %s", seg.c_str(), name_of(i).c_str());
        break;
      }
      if (v == setup::MotionJudge::Verdict::ambiguous) {
        say("two sensors moved at once (%s; %s): hold still, then move only %s",
            name_of(static_cast<std::size_t>(judge.winner())).c_str(),
            name_of(static_cast<std::size_t>(judge.second())).c_str(), seg.c_str());
        settling = true;
        continue;
      }
      const auto waited = std::chrono::steady_clock::now() - started;
      if (!reminded && waited > kRemindAfter) {
        reminded = true;
        say("nothing moved alone yet for %s: move it more, or Enter if it has no sensor",
            seg.c_str());
      }
      if (o.timeout_s > 0 && waited > std::chrono::duration<double>(o.timeout_s)) {
        say("skipped %s: no sensor moved alone in %.0f s", seg.c_str(), o.timeout_s);
        skipped[index(ask.segment)] = true;
        break;
      }
    }
    k = next_k;
  }
  listener.stop();  // free the ports for mocapd

  setup::RigPlan plan;
  bool all_mag = true;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (skipped[s]) plan.no_sensor.emplace_back(kSegmentNames[s]);
    for (std::size_t i = 0; i < cands.size(); ++i) {
      if (segment_of[i] != s) continue;
      daemon::SensorConfig c = cands[i].sensor;
      c.name = std::string(kSegmentNames[s]);
      c.segment = c.name;
      plan.sensors.push_back(c);
      all_mag = all_mag && (listener.meter().seen(i).fields & kFieldMag);
    }
  }
  for (std::size_t i = 0; i < cands.size(); ++i) {
    if (label[i] && segment_of[i] < 0) {
      say("left out (never moved alone): %s", name_of(i).c_str());
      left_out.push_back(cands[i].what);
    }
  }
  plan.left_out = left_out;
  plan.silent = silent;
  plan.use_mag = all_mag;
  if (plan.sensors.empty()) {
    say("no sensor was assigned: no rig written");
    return 1;
  }
  const fs::path out(o.out);
  plan.calibration_file = out.stem().string() + "-calibration.toml";
  const std::string tmp = o.out + ".tmp";
  {
    std::ofstream f(tmp);
    f << setup::rig_toml(plan);
    if (!f.good()) {
      std::fprintf(stderr, "mocap setup: cannot write %s\n", tmp.c_str());
      return 1;
    }
  }
  std::error_code ec;
  fs::rename(tmp, out, ec);
  if (ec) {
    std::fprintf(stderr, "mocap setup: cannot write %s: %s\n", o.out.c_str(), ec.message().c_str());
    return 1;
  }
  say("wrote %s: %zu sensor%s", o.out.c_str(), plan.sensors.size(),
      plan.sensors.size() == 1 ? "" : "s");
  // The check mocapd --check-config makes.
  daemon::ConfigErrors errors;
  const auto cfg = daemon::load_config(o.out, {}, errors, &daemon::default_validators());
  for (const auto& w : errors.warnings)
    say("warning: %s", w.c_str());
  if (!cfg) {
    std::fprintf(stderr, "%s", errors.to_string().c_str());
    say("checked %s: INVALID (%zu problem%s)", o.out.c_str(), errors.errors.size(),
        errors.errors.size() == 1 ? "" : "s");
    return 1;
  }
  say("checked %s: OK (%zu sensor%s); run it with: mocapd --config %s", o.out.c_str(),
      cfg->sensors.size(), cfg->sensors.size() == 1 ? "" : "s", o.out.c_str());
  return 0;
}

}  // namespace

void add_setup(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<SetupOptions>();
  CLI::App* c = cli::add_command(
      app, "setup",
      "assign sensors to body segments by moving them, and write the rig file (docs/setup.md)");
  c->add_option("--out", o->out, "the rig file to write")->capture_default_str();
  c->add_flag("--force", o->force, "replace --out if it exists");
  cli::add_multi(*c, "--port", o->ports,
                 "also listen on this serial port (PATH, or PATH@DRIVER: witmotion, line, xbus; "
                 "without a driver it is probed)");
  c->add_flag("--no-scan", o->no_scan,
              "do not look for serial, HID and USB devices by their USB ids (only --port and "
              "SlimeVR)");
  c->add_option("--slimevr", o->slimevr,
                "HOST:PORT where SlimeVR trackers send (\"\" = no SlimeVR)")
      ->capture_default_str();
  c->add_option("--slimevr-listen", o->slimevr_listen_s,
                "seconds to listen for SlimeVR trackers' hello")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  c->add_option("--probe", o->probe_s,
                "seconds a device gets to send samples with each driver setting tried")
      ->check(CLI::Range(0.1, 30.0))
      ->capture_default_str();
  c->add_option("--segments", o->segments,
                "segments to ask for, comma-separated (default: all 16, hands and feet first)");
  c->add_option("--window", o->window_s, "motion window, seconds")
      ->check(CLI::Range(0.05, 5.0))
      ->capture_default_str();
  c->add_option("--hold", o->hold_s, "how long a sensor must move alone to be assigned, seconds")
      ->check(CLI::Range(0.05, 30.0))
      ->capture_default_str();
  c->add_option("--threshold", o->threshold_dps,
                "mean angular speed over a window that counts as moving, deg/s")
      ->check(CLI::Range(1.0, 2000.0))
      ->capture_default_str();
  c->add_option("--dominance", o->dominance,
                "how many times faster than any other the moving sensor must be")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  c->add_option("--timeout", o->timeout_s,
                "seconds per segment before it is skipped (0 = wait for an answer)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  c->callback([o, &exit_code] { exit_code = run_setup(*o); });
}

}  // namespace mocap::cmd
