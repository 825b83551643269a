// `mocap setup` end to end (issue 30 part 2): simulated sensors through the real drivers (WitMotion
// and a DIY line-protocol board on pseudo-terminals, SlimeVR boards over UDP) strapped on a
// virtual performer who reads the prompts from setup's stdout and moves the segment asked for
// (and, once, both hands at the first prompt; "skip" on stdin for the neck, which has no sensor).
// The rig setup writes must put every sensor on its segment, leave out and name the sensor
// lying on the table, and run in mocapd: every sensor streams, and moving a segment turns that
// segment (and what hangs from it) in mocapd's pose stream while the rest stays still.
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../common/e2e_process.hpp"
#include "../common/free_port.hpp"
#include "../common/raw_unix_call.hpp"
#include "../common/temp_dir.hpp"
#include "live_performer.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/devsim/sim_slimevr.hpp"

namespace mocap {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

/// A program with its stdin and stdout on pipes (stderr to a file).
struct Piped {
  Piped(const std::vector<std::string>& argv, const std::string& err_file) {
    int in[2], out[2];
    EXPECT_EQ(::pipe(in), 0);
    EXPECT_EQ(::pipe(out), 0);
    pid = ::fork();
    if (pid == 0) {
      ::dup2(in[0], 0);
      ::dup2(out[1], 1);
      const int e = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(e, 2);
      ::close(in[1]);
      ::close(out[0]);
      std::vector<char*> a;
      for (const auto& s : argv)
        a.push_back(const_cast<char*>(s.c_str()));
      a.push_back(nullptr);
      ::execv(a[0], a.data());
      ::_exit(127);
    }
    ::close(in[0]);
    ::close(out[1]);
    to = in[1];
    from = out[0];
  }
  ~Piped() {
    if (to >= 0) ::close(to);
    ::close(from);
    if (pid > 0 && ::waitpid(pid, nullptr, WNOHANG) == 0) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  /// The next line of its stdout ("" and false at the end or after timeout).
  bool line(std::string& out, std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto nl = buf.find('\n');
      if (nl != std::string::npos) {
        out = buf.substr(0, nl);
        buf.erase(0, nl + 1);
        return true;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          end - std::chrono::steady_clock::now());
      if (left.count() <= 0) return false;
      pollfd p{from, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char b[4096];
      const ssize_t n = ::read(from, b, sizeof b);
      if (n <= 0) return false;
      buf.append(b, static_cast<std::size_t>(n));
    }
  }
  void answer(const std::string& text) {
    const std::string l = text + "\n";
    EXPECT_EQ(::write(to, l.data(), l.size()), static_cast<ssize_t>(l.size()));
  }
  int wait() {
    int st = 0;
    ::waitpid(pid, &st, 0);
    pid = -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  pid_t pid = -1;
  int to = -1, from = -1;
  std::string buf;
};

/// The sensors strapped on the performer: where each one is and what it is called in the rig.
struct Strapped {
  int segment;       ///< -1: lying on the table
  std::string port;  ///< serial link, or "" for a SlimeVR IMU
  std::string mac;
  int tracker = 0;
};

/// Segments under s (s included).
bool below(int k, int s) {
  for (; k != kNoParent; k = kSegmentParent[k])
    if (k == s) return true;
  return false;
}

}  // namespace

TEST(MocapSetup, AssignsEverySensorByMotionAndMocapdRunsTheRig) {
  test::TempDir dir("setup");
  test::LivePerformer performer;
  std::vector<Strapped> truth;
  std::vector<std::unique_ptr<SimulatedDevice>> serial;
  std::vector<std::unique_ptr<SimSlimeTracker>> boards;
  std::vector<std::string> ports;
  // WitMotion sensors on ptys: half named with their driver, half probed.
  const Segment witmotion[] = {Segment::hand_l, Segment::forearm_l, Segment::upper_arm_l,
                               Segment::hand_r, Segment::forearm_r, Segment::upper_arm_r,
                               Segment::head,   Segment::torso};
  for (const Segment s : witmotion) {
    SimOptions o;
    o.protocol = "witmotion";
    o.rate_hz = 100;
    o.pty_link = dir.file("tty_" + std::string(name(s)));
    o.motion_source = performer.motion_of(index(s));
    serial.push_back(std::make_unique<SimulatedDevice>(o));
    ports.push_back(o.pty_link + (serial.size() % 2 ? "@witmotion" : ""));
    truth.push_back({index(s), o.pty_link, "", 0});
  }
  {  // a DIY board speaking the line protocol on the pelvis: found by probing
    SimOptions o;
    o.protocol = "line";
    o.rate_hz = 100;
    o.pty_link = dir.file("tty_pelvis");
    o.motion_source = performer.motion_of(index(Segment::pelvis));
    serial.push_back(std::make_unique<SimulatedDevice>(o));
    ports.push_back(o.pty_link);
    truth.push_back({index(Segment::pelvis), o.pty_link, "", 0});
  }
  // SlimeVR boards on the legs (two with an extension IMU), and one left on the table.
  const int slime_port = test::free_loopback_port(SOCK_DGRAM);
  const std::vector<std::pair<std::string, std::vector<int>>> board_segments = {
      {"02:5E:00:00:00:11", {index(Segment::thigh_l), index(Segment::shank_l)}},
      {"02:5E:00:00:00:12", {index(Segment::foot_l)}},
      {"02:5E:00:00:00:13", {index(Segment::thigh_r), index(Segment::shank_r)}},
      {"02:5E:00:00:00:14", {index(Segment::foot_r)}},
      {"02:5E:00:00:00:15", {-1}}};
  for (const auto& [mac, segs] : board_segments) {
    SimSlimeOptions o;
    o.server = "127.0.0.1:" + std::to_string(slime_port);
    o.mac = mac;
    o.sensors = static_cast<int>(segs.size());
    for (std::size_t k = 0; k < segs.size(); ++k) {
      o.sensor_motions.push_back(segs[k] >= 0
                                     ? performer.motion_of(segs[k])
                                     : std::shared_ptr<const Motion>(make_motion("static")));
      truth.push_back({segs[k], "", mac, static_cast<int>(k)});
    }
    boards.push_back(std::make_unique<SimSlimeTracker>(o));
  }
  for (auto& d : serial)
    d->start();
  for (auto& b : boards)
    b->start();

  // mocap setup, with the performer reading its prompts.
  const std::string rig = dir.file("rig.toml");
  std::vector<std::string> argv = {test::kBinDir + "mocap",
                                   "setup",
                                   "--out",
                                   rig,
                                   "--no-scan",
                                   "--slimevr",
                                   "127.0.0.1:" + std::to_string(slime_port),
                                   "--slimevr-listen",
                                   "1.5",
                                   "--probe",
                                   "0.6",
                                   "--timeout",
                                   "20"};
  for (const auto& p : ports) {
    argv.push_back("--port");
    argv.push_back(p);
  }
  const auto t_setup = std::chrono::steady_clock::now();
  Piped setup(argv, dir.file("setup.err"));
  std::vector<std::string> lines;
  std::map<std::string, int> prompts;
  bool fumbled = false;
  std::string l;
  while (setup.line(l, 30s)) {
    lines.push_back(l);
    if (l.rfind("move ", 0) == 0) {
      const std::string seg = l.substr(5, l.find(':') - 5);
      ++prompts[seg];
      performer.stop();
      const auto s = segment_from_name(seg);
      ASSERT_TRUE(s) << l;
      if (*s == Segment::neck) {
        setup.answer("skip");  // nothing strapped there
      } else if (*s == Segment::hand_l && !fumbled) {
        fumbled = true;  // both hands at once: setup must ask again
        performer.move(index(Segment::hand_l));
        performer.move(index(Segment::hand_r));
      } else {
        performer.move(index(*s));
      }
    } else if (l.rfind("two sensors moved at once", 0) == 0 || l.rfind("assigned ", 0) == 0) {
      performer.stop();
    }
  }
  std::string all;
  for (const auto& x : lines)
    all += x + "\n";
  ASSERT_EQ(setup.wait(), 0) << all << test::slurp_file(dir.file("setup.err"));
  const double setup_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_setup).count();
  std::printf("%s", all.c_str());
  performer.stop();

  // What setup said: 16 sensors heard, asked again after the fumble, the table's sensor named.
  EXPECT_NE(all.find("heard 16 sensors"), std::string::npos) << all;
  EXPECT_EQ(prompts["hand_l"], 2) << all;
  EXPECT_EQ(prompts["neck"], 1) << all;
  EXPECT_NE(all.find("two sensors moved at once"), std::string::npos) << all;
  EXPECT_NE(all.find("skipped neck"), std::string::npos) << all;
  EXPECT_NE(all.find("left out (never moved alone): s16 SlimeVR tracker 02:5E:00:00:00:15"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("checked " + rig + ": OK (15 sensors)"), std::string::npos) << all;

  // The rig: every strapped sensor on its segment, ports and MACs as the devices are reached.
  daemon::ConfigErrors errors;
  const auto cfg = daemon::load_config(rig, {}, errors, &daemon::default_validators());
  ASSERT_TRUE(cfg) << errors.to_string() << test::slurp_file(rig);
  ASSERT_EQ(cfg->sensors.size(), 15u) << test::slurp_file(rig);
  for (const Strapped& t : truth) {
    int found = 0;
    for (const auto& s : cfg->sensors) {
      const bool same = t.port.empty() ? s.driver == "slimevr" && s.options.at("mac") == t.mac &&
                                             s.options.at("tracker") == std::to_string(t.tracker)
                                       : s.port == t.port;
      if (!same) continue;
      ++found;
      ASSERT_GE(t.segment, 0) << "the sensor on the table was assigned to " << s.segment;
      EXPECT_EQ(s.segment, std::string(kSegmentNames[t.segment])) << (t.port + t.mac);
      EXPECT_EQ(s.name, s.segment);
    }
    EXPECT_EQ(found, t.segment >= 0 ? 1 : 0) << (t.port + t.mac);
  }
  for (const auto& s : cfg->sensors)
    if (s.segment == "pelvis") {
      EXPECT_EQ(s.driver, "line");  // found by probing
    }
  EXPECT_FALSE(cfg->filter.use_mag);  // SlimeVR trackers send orientations, no magnetometer

  // mocapd runs the rig: every sensor streams; moving a segment turns it in the pose stream.
  const auto t_mocapd = std::chrono::steady_clock::now();
  const int json_port = test::free_loopback_port(SOCK_STREAM);
  const std::string control = dir.file("ctl.sock");
  const pid_t daemon = test::spawn(
      {test::kBinDir + "mocapd", "--config", rig, "--set",
       "daemon.control_socket=\"" + control + "\"", "--set",
       "outputs.json.port=" + std::to_string(json_port), "--set", "outputs.posture.enabled=false",
       "--set", "calibration.file=\"" + dir.file("cal.toml") + "\"", "--set",
       "recording.directory=\"" + dir.path() + "\""},
      dir.file("mocapd.log"));
  ASSERT_GT(daemon, 0);
  int streaming = 0;
  nlohmann::json status;
  for (int i = 0; i < 1000 && streaming < 15; ++i) {
    std::this_thread::sleep_for(20ms);
    const std::string reply = test::raw_unix_call(control, "status\n");
    if (reply.rfind("{", 0) != 0) continue;
    status = nlohmann::json::parse(reply);
    streaming = 0;
    for (const auto& s : status["sensors"])
      streaming += s["state"] == "streaming" && s["segment"] == s["name"];
  }
  EXPECT_EQ(streaming, 15) << status.dump() << test::slurp_file(dir.file("mocapd.log.err"));

  std::vector<bool> sensored(kSegmentCount, false);
  for (const auto& s : cfg->sensors)
    sensored[index(*segment_from_name(s.segment))] = true;
  // Joints that do not hang from one another turn together, each by its own amplitude, so
  // each segment's turn in the stream names the joint that turned it (a swap would show).
  const std::vector<std::vector<Segment>> groups = {
      {Segment::hand_l, Segment::hand_r, Segment::foot_l, Segment::foot_r, Segment::head},
      {Segment::forearm_l, Segment::forearm_r, Segment::shank_l, Segment::shank_r},
      {Segment::upper_arm_l, Segment::upper_arm_r, Segment::thigh_l, Segment::thigh_r},
      {Segment::torso},
      {Segment::pelvis}};
  const double amplitude_deg[] = {20, 35, 50, 65, 80};
  std::string report;
  double still_worst = 0;  // the most a segment turned that should have stayed still
  for (const auto& group : groups) {
    while (!performer.resting())
      std::this_thread::sleep_for(10ms);
    // The motion starts once the first frame (the rest pose every turn is measured from) has
    // arrived: a reader late under load would otherwise take its first frame mid-swing and see
    // up to twice the amplitude.
    std::promise<void> first_frame;
    std::thread mover([&, first = first_frame.get_future()]() mutable {
      first.wait_for(10s);
      std::this_thread::sleep_for(100ms);
      for (std::size_t g = 0; g < group.size(); ++g)
        performer.move(index(group[g]), amplitude_deg[g] * M_PI / 180, 2.0);
      performer.stop();  // one cycle
      while (!performer.resting())
        std::this_thread::sleep_for(10ms);
      std::this_thread::sleep_for(100ms);
    });
    const auto frames = test::read_json_lines(static_cast<uint16_t>(json_port), 100,
                                              [&] { first_frame.set_value(); });
    mover.join();
    ASSERT_GE(frames.size(), 80u);
    std::array<double, kSegmentCount> turned{};
    for (const auto& f : frames) {
      for (int k = 0; k < kSegmentCount; ++k) {
        const auto& a = frames.front()["segments"][k]["q"];
        const auto& b = f["segments"][k]["q"];
        const Eigen::Quaterniond qa(a[0], a[1], a[2], a[3]), qb(b[0], b[1], b[2], b[3]);
        turned[k] = std::max(turned[k], qa.angularDistance(qb) * 180 / M_PI);
      }
    }
    for (int k = 0; k < kSegmentCount; ++k) {
      if (!sensored[k]) continue;
      double expected = 0;  // the amplitude of the turning joint it hangs from, if any
      for (std::size_t g = 0; g < group.size(); ++g)
        if (below(k, index(group[g]))) expected = amplitude_deg[g];
      // 3 deg and 6 %: the filters' overshoot on a 1000 deg/s nod stays inside, and the
      // amplitudes' windows (15 deg apart) do not touch.
      EXPECT_NEAR(turned[k], expected, 3.0 + 0.06 * expected)
          << kSegmentNames[k] << " in the group of " << kSegmentNames[index(group[0])];
      if (expected == 0) still_worst = std::max(still_worst, turned[k]);
    }
    for (const Segment seg : group) {
      char b[64];
      std::snprintf(b, sizeof b, " %s %.1f", std::string(name(seg)).c_str(), turned[index(seg)]);
      report += b;
    }
  }
  ::kill(daemon, SIGTERM);
  EXPECT_EQ(test::wait_exit(daemon, 30), 0);
  std::printf(
      "[figures] mocap setup: %zu lines in %.1f s; mocapd on its rig, %.1f s: each segment "
      "turned by (deg; asked 20, 35, 50, 65, 80 within a group):%s; still ones at most %.2f\n",
      lines.size(), setup_s,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_mocapd).count(),
      report.c_str(), still_worst);
}

}  // namespace mocap
