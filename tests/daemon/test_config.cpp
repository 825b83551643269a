// Config loader: defaults, typed reads, file:line:column errors, unknown keys with suggestions,
// range checks, --set overrides and the --print-config round trip.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "mocap/daemon/config.hpp"

using namespace mocap::daemon;

namespace {

std::optional<Config> parse(const std::string& text, ConfigErrors& errs,
                            std::vector<std::string> sets = {}) {
  return parse_config(text, "rig.toml", sets, errs);
}

const char* kRig = R"(
[pipeline]
rate_hz = 200

[[sensor]]
name = "pelvis"
driver = "witmotion"
port = "/dev/ttyUSB0"
segment = "pelvis"

[[sensor]]
name = "left_thigh"
driver = "xbus"
vid = 0x2639
pid = 0x0300
segment = "thigh_l"
axis_remap = "-y,x,z"
site_normal = [0.0, 1.0, 0.0]
gyr_scale = [1.004, 0.995, 1.0]
[sensor.options]
quat_order = "wxyz"
)";

}  // namespace

TEST(Config, EmptyFileGivesDefaults) {
  ConfigErrors errs;
  auto c = parse("", errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_DOUBLE_EQ(c->pipeline.rate_hz, 120.0);
  EXPECT_EQ(c->outputs.json.bind, "127.0.0.1");
  EXPECT_TRUE(c->sensors.empty());
}

// The body corrections removed after the real-motion measurements (docs/accuracy.md): older
// configs and recordings still load; each such key is named in a warning, never silently taken.
TEST(Config, RemovedBodyCorrectionKeysLoadWithAWarning) {
  for (const char* text :
       {"[calibration]\nheading_coupling = false\n", "[calibration]\nrefine_hinges = true\n",
        "[calibration]\nrelative_mag_heading = false\n", "[body]\nenforce_limits = true\n"}) {
    ConfigErrors errs;
    EXPECT_TRUE(parse(text, errs)) << text << errs.to_string();
    const std::string t = text;
    const std::string key = t.substr(t.find('\n') + 1, t.find(' ') - t.find('\n') - 1);
    ASSERT_EQ(errs.warnings.size(), 1u) << text;
    EXPECT_NE(errs.warnings[0].find(key + ": removed"), std::string::npos) << errs.warnings[0];
  }
  ConfigErrors errs;
  EXPECT_TRUE(parse("", errs));
  EXPECT_TRUE(errs.warnings.empty());
}

TEST(Config, CalibrationHeadingSourceAndSiteNormals) {
  ConfigErrors errs;
  auto d = parse("", errs);
  ASSERT_TRUE(d) << errs.to_string();
  EXPECT_EQ(d->calibration.heading, mocap::HeadingSource::mount_normals);  // the default
  auto c = parse(kRig, errs, {"calibration.heading=pelvis_sensor"});
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->calibration.heading, mocap::HeadingSource::pelvis_sensor);
  EXPECT_FALSE(c->sensors[0].site_normal);  // the segment's standard site
  ASSERT_TRUE(c->sensors[1].site_normal);
  EXPECT_DOUBLE_EQ((*c->sensors[1].site_normal)[1], 1.0);
  // A misspelt source names the key and suggests the nearest.
  ConfigErrors e1;
  EXPECT_FALSE(parse("[calibration]\nheading = \"mount_normal\"\n", e1));
  EXPECT_NE(e1.to_string().find("rig.toml:2:11: calibration.heading"), std::string::npos)
      << e1.to_string();
  EXPECT_NE(e1.to_string().find("did you mean 'mount_normals'"), std::string::npos);
  // A normal must be three numbers, not all zero; the error names the sensor and the line.
  for (const char* bad : {"[0, 0, 0]", "[1, 0]", "\"up\"", "[1, \"a\", 0]"}) {
    std::string rig = kRig;
    rig.replace(rig.find("[0.0, 1.0, 0.0]"), 15, bad);
    ConfigErrors e2;
    EXPECT_FALSE(parse(rig, e2)) << bad;
    EXPECT_NE(e2.to_string().find("rig.toml:18:15: sensor[1].site_normal"), std::string::npos)
        << e2.to_string();
  }
}

TEST(Config, GyroScaleIsOptionalAndWithinTwentyPercent) {
  ConfigErrors errs;
  auto c = parse(kRig, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_FALSE(c->sensors[0].gyr_scale);  // uncalibrated
  ASSERT_TRUE(c->sensors[1].gyr_scale);
  EXPECT_DOUBLE_EQ((*c->sensors[1].gyr_scale)[0], 1.004);
  EXPECT_DOUBLE_EQ((*c->sensors[1].gyr_scale)[1], 0.995);
  for (const char* bad : {"[1.0, 1.3, 1.0]", "[1, 1]", "[0, 1, 1]", "1.0"}) {
    std::string rig = kRig;
    rig.replace(rig.find("[1.004, 0.995, 1.0]"), 19, bad);
    ConfigErrors e;
    EXPECT_FALSE(parse(rig, e)) << bad;
    EXPECT_NE(e.to_string().find("rig.toml:19:13: sensor[1].gyr_scale"), std::string::npos)
        << e.to_string();
  }
}

TEST(Config, ReadsSensors) {
  ConfigErrors errs;
  auto c = parse(kRig, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_DOUBLE_EQ(c->pipeline.rate_hz, 200.0);
  ASSERT_EQ(c->sensors.size(), 2u);
  EXPECT_EQ(c->sensors[1].vid, 0x2639);
  EXPECT_EQ(c->sensors[1].segment, "thigh_l");
  EXPECT_EQ(c->sensors[1].options.at("quat_order"), "wxyz");
}

TEST(Config, UnknownKeySuggestsNearestWithPosition) {
  ConfigErrors errs;
  auto c = parse("[pipeline]\nrate_hx = 100\n", errs);
  ASSERT_FALSE(c);
  ASSERT_EQ(errs.errors.size(), 1u);
  const auto& e = errs.errors[0];
  EXPECT_EQ(e.file, "rig.toml");
  EXPECT_EQ(e.line, 2);
  EXPECT_EQ(e.column, 11);  // toml++ places a key-value pair's source at its value
  EXPECT_EQ(e.key, "pipeline.rate_hx");
  EXPECT_NE(e.message.find("did you mean 'rate_hz'"), std::string::npos) << e.message;
  EXPECT_EQ(e.to_string().rfind("rig.toml:2:", 0), 0u) << e.to_string();
}

TEST(Config, UnknownSectionAndSegmentSuggestions) {
  ConfigErrors errs;
  auto c = parse(
      "[outptus]\n[[sensor]]\nname=\"a\"\ndriver=\"line\"\nport=\"/dev/x\"\n"
      "segment=\"thigh_left\"\n",
      errs);
  ASSERT_FALSE(c);
  ASSERT_EQ(errs.errors.size(), 2u) << errs.to_string();
  std::string all = errs.to_string();
  EXPECT_NE(all.find("did you mean 'outputs'"), std::string::npos) << all;
  EXPECT_NE(all.find("sensor[0].segment"), std::string::npos) << all;
  EXPECT_NE(all.find("rig.toml:6:"), std::string::npos) << all;
}

TEST(Config, RangeAndTypeChecks) {
  ConfigErrors errs;
  auto c = parse(
      "[pipeline]\nrate_hz = 0\nstale_after_ms = \"x\"\nrealtime_priority = 80\n"
      "[outputs.json]\nport = 70000\n"
      "bind = \"localhost:1\"\n",
      errs);
  ASSERT_FALSE(c);
  std::string all = errs.to_string();
  EXPECT_EQ(errs.errors.size(), 5u) << all;
  EXPECT_NE(all.find("pipeline.realtime_priority: 80 is out of range [0, 49]"), std::string::npos)
      << all;
  EXPECT_NE(all.find("pipeline.rate_hz: 0 is out of range"), std::string::npos) << all;
  EXPECT_NE(all.find("pipeline.stale_after_ms: expected a number"), std::string::npos) << all;
  EXPECT_NE(all.find("outputs.json.port: 70000 is out of range"), std::string::npos) << all;
  EXPECT_NE(all.find("not an IPv4 address"), std::string::npos) << all;
}

TEST(Config, SensorConsistency) {
  ConfigErrors errs;
  auto c = parse(R"([[sensor]]
name = "a"
driver = "line"
segment = "head"
axis_remap = "x,x,z"
[[sensor]]
name = "a"
driver = "line"
port = "/dev/b"
vid = 1
pid = 2
segment = "head"
)",
                 errs);
  ASSERT_FALSE(c);
  std::string all = errs.to_string();
  EXPECT_NE(all.find("needs either port or vid and pid"), std::string::npos) << all;
  EXPECT_NE(all.find("not a permutation"), std::string::npos) << all;
  EXPECT_NE(all.find("duplicate sensor name"), std::string::npos) << all;
  EXPECT_NE(all.find("already has a sensor"), std::string::npos) << all;
  EXPECT_NE(all.find("not both"), std::string::npos) << all;
}

TEST(Config, SyntaxErrorHasPosition) {
  ConfigErrors errs;
  auto c = parse("[pipeline]\nrate_hz = = 3\n", errs);
  ASSERT_FALSE(c);
  ASSERT_EQ(errs.errors.size(), 1u);
  EXPECT_EQ(errs.errors[0].line, 2);
  EXPECT_GT(errs.errors[0].column, 0);
}

TEST(Config, SetOverridesAnyKey) {
  ConfigErrors errs;
  auto c = parse(kRig, errs,
                 {"outputs.json.port=7400", "sensor.pelvis.port=/dev/pts/9", "sensor.1.baud=115200",
                  "pipeline.publish_every_sample=true", "demo.motion=dance"});
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->outputs.json.port, 7400);
  EXPECT_EQ(c->sensors[0].port, "/dev/pts/9");
  EXPECT_EQ(c->sensors[1].baud, 115200);
  EXPECT_TRUE(c->pipeline.publish_every_sample);
  EXPECT_EQ(c->demo.motion, "dance");
}

TEST(Config, SetErrorsAreReported) {
  ConfigErrors errs;
  EXPECT_FALSE(parse(kRig, errs, {"outputs.json.prot=1"}));
  EXPECT_NE(errs.to_string().find("did you mean 'port'"), std::string::npos) << errs.to_string();
  errs = {};
  EXPECT_FALSE(parse(kRig, errs, {"sensor.nobody.port=x"}));
  EXPECT_NE(errs.to_string().find("no sensor 'nobody'"), std::string::npos) << errs.to_string();
  errs = {};
  EXPECT_FALSE(parse(kRig, errs, {"noequals"}));
  errs = {};
  EXPECT_FALSE(parse(kRig, errs, {"pipeline.rate_hz=abc"}));
  EXPECT_NE(errs.to_string().find("expected a number"), std::string::npos) << errs.to_string();
}

TEST(Config, PrintedConfigParsesBackIdentically) {
  ConfigErrors errs;
  auto c = parse(kRig, errs);
  ASSERT_TRUE(c);
  const std::string printed = config_to_toml(*c);
  auto c2 = parse_config(printed, "printed", {}, errs);
  ASSERT_TRUE(c2) << errs.to_string() << printed;
  const std::string again = config_to_toml(*c2);
  EXPECT_EQ(again.substr(again.find('\n')), printed.substr(printed.find('\n')));
  EXPECT_EQ(c2->sensors[1].axis_remap, "-y,x,z");
  EXPECT_EQ(c2->sensors[1].site_normal, c->sensors[1].site_normal);
  EXPECT_EQ(c2->sensors[1].gyr_scale, c->sensors[1].gyr_scale);
  EXPECT_FALSE(c2->sensors[0].gyr_scale);
}

TEST(Config, ExampleRigsAreValid) {
  namespace fs = std::filesystem;
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::path(MOCAP_SOURCE_DIR) / "config")) {
    if (e.path().extension() != ".toml") continue;
    ConfigErrors errs;
    EXPECT_TRUE(load_config(e.path().string(), {}, errs)) << errs.to_string();
    ++n;
  }
  EXPECT_GE(n, 1);
}

// Issue 22 item 7: a serial sensor asking more than its baud carries is warned about.
TEST(Config, SerialRateBeyondTheBaudIsWarned) {
  const std::string base =
      "[[sensor]]\nname = \"w\"\ndriver = \"witmotion\"\n"
      "port = \"/dev/ttyUSB0\"\nrate_hz = 100\n";
  ConfigErrors errs;
  auto c = parse_config(base, "w.toml", {}, errs, &default_validators());
  ASSERT_TRUE(c) << errs.to_string();
  ASSERT_EQ(errs.warnings.size(), 1u);
  EXPECT_NE(errs.warnings[0].find("9600 baud"), std::string::npos) << errs.warnings[0];
  EXPECT_NE(errs.warnings[0].find("at most 14 samples/s"), std::string::npos) << errs.warnings[0];
  EXPECT_NE(errs.warnings[0].find("sensor"), std::string::npos) << errs.warnings[0];
  // At 115200 it fits; a UDP or HID sensor has no baud; Xbus at 200 Hz on 115200 8N2 does not.
  for (const char* ok : {"baud = 115200\n", "rate_hz = 10\n"}) {
    ConfigErrors e2;
    std::string text = base;
    if (std::string(ok).rfind("rate_hz", 0) == 0)
      text.replace(text.find("rate_hz = 100"), 13, "rate_hz = 10");
    else
      text += ok;
    ASSERT_TRUE(parse_config(text, "w.toml", {}, e2, &default_validators())) << e2.to_string();
    EXPECT_TRUE(e2.warnings.empty()) << ok << e2.warnings.at(0);
  }
  ConfigErrors ex;
  ASSERT_TRUE(
      parse_config("[[sensor]]\nname = \"x\"\ndriver = \"xbus\"\nport = "
                   "\"/dev/ttyUSB0\"\nrate_hz = 200\n",
                   "x.toml", {}, ex, &default_validators()));
  ASSERT_EQ(ex.warnings.size(), 1u);
  EXPECT_NE(ex.warnings[0].find("115200 baud"), std::string::npos) << ex.warnings[0];
}

TEST(Config, ExampleRigsFitTheirLinks) {
  namespace fs = std::filesystem;
  for (const auto& e : fs::directory_iterator(fs::path(MOCAP_SOURCE_DIR) / "config")) {
    if (e.path().extension() != ".toml") continue;
    ConfigErrors errs;
    EXPECT_TRUE(load_config(e.path().string(), {}, errs, &default_validators()))
        << errs.to_string();
    EXPECT_TRUE(errs.warnings.empty()) << e.path() << ": " << errs.warnings.at(0);
  }
}

TEST(Config, MissingFile) {
  ConfigErrors errs;
  EXPECT_FALSE(load_config("/nonexistent/rig.toml", {}, errs));
  EXPECT_NE(errs.to_string().find("cannot open"), std::string::npos);
}

TEST(Config, NearestName) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3);
  EXPECT_EQ(nearest_name("rate_hx", {"rate_hz", "stale_after_ms"}), "rate_hz");
  EXPECT_EQ(nearest_name("zzzzzzzz", {"rate_hz"}), "");
}

TEST(Config, ValidatorsReportAtTheKey) {
  ConfigValidators v;
  v.sensor = [](const SensorConfig& s) {
    return s.driver == "witmotion" ? std::string() : "unknown driver '" + s.driver + "'";
  };
  ConfigErrors errs;
  auto c = parse_config(
      "[filter]\ntau_mag_s = 12\nuse_mag = false\n[[sensor]]\nname=\"a\"\n"
      "driver=\"witmotion\"\nport=\"/dev/x\"\n",
      "rig.toml", {}, errs, &v);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->filter.params.heading.tau_mag_s, 12.0);
  EXPECT_FALSE(c->filter.use_mag);
  // Round trip through print-config keeps the filter parameter as a number.
  auto c2 = parse_config(config_to_toml(*c), "printed", {}, errs, &v);
  ASSERT_TRUE(c2) << errs.to_string();
  EXPECT_EQ(c2->filter.params.heading.tau_mag_s, 12.0);

  c = parse_config(
      "[filter]\ntau_acc_z = 1.0\n[[sensor]]\nname=\"a\"\ndriver=\"bogus\"\n"
      "port=\"/dev/x\"\n",
      "rig.toml", {}, errs, &v);
  ASSERT_FALSE(c);
  const std::string all = errs.to_string();
  EXPECT_NE(all.find("rig.toml:2:13: filter.tau_acc_z: unknown key (did you mean 'tau_acc_s'?)"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("rig.toml:5:8: sensor[0].driver: unknown driver 'bogus'"), std::string::npos)
      << all;
}

namespace {

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("mocap-config-test-" + std::to_string(::getpid()) + "-" + name);
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace

TEST(Config, BodyModelAndJointLimitsInlineAndFromFiles) {
  ConfigErrors errs;
  // Inline: height, a segment override and a joint-limit override.
  auto c = parse(
      "[body]\nheight_m = 1.62\n[body.segment.forearm_l]\njoint_offset_m = [0, 0, -0.31]\n"
      "[body.joint.knee_l]\nb_deg = [-5, 130]\n",
      errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_DOUBLE_EQ(c->body.model.height_m, 1.62);
  const int forearm = mocap::index(mocap::Segment::forearm_l);
  ASSERT_TRUE(c->body.model.joint_offset_m[forearm]);
  EXPECT_DOUBLE_EQ(c->body.model.joint_offset_m[forearm]->z(), -0.31);
  const int knee = mocap::index(mocap::Segment::shank_l);
  EXPECT_DOUBLE_EQ(c->body.limits.joint[knee].b_max_deg, 130);
  EXPECT_NE(mocap::default_joint_limits().joint[knee].b_max_deg, 130);
  EXPECT_EQ(c->body.limits.joint[mocap::index(mocap::Segment::shank_r)].b_max_deg,
            mocap::default_joint_limits().joint[mocap::index(mocap::Segment::shank_r)].b_max_deg);
  // The printed configuration inlines every override and parses back to the same body.
  const std::string printed = config_to_toml(*c);
  auto c2 = parse_config(printed, "printed", {}, errs);
  ASSERT_TRUE(c2) << errs.to_string() << printed;
  EXPECT_EQ(c2->body.model.joint_offset_m[forearm], c->body.model.joint_offset_m[forearm]);
  EXPECT_DOUBLE_EQ(c2->body.limits.joint[knee].b_max_deg, 130);
  EXPECT_DOUBLE_EQ(c2->body.model.height_m, 1.62);

  // Files (the shipped formats), then inline keys over them.
  const std::string body = write_file(
      "body.toml", "height_m = 1.90\n[segment.shank_r]\njoint_offset_m = [0, 0, -0.5]\n");
  const std::string limits = write_file("limits.toml", "[joint.elbow_r]\nb_deg = [-170, 0]\n");
  auto f = parse("[body]\nmodel = \"" + body + "\"\njoint_limits = \"" + limits +
                     "\"\n[body.segment.shank_l]\njoint_offset_m = [0, 0, -0.45]\n",
                 errs);
  ASSERT_TRUE(f) << errs.to_string();
  EXPECT_DOUBLE_EQ(f->body.model.height_m, 1.90);
  EXPECT_DOUBLE_EQ(f->body.model.joint_offset_m[mocap::index(mocap::Segment::shank_r)]->z(), -0.5);
  EXPECT_DOUBLE_EQ(f->body.model.joint_offset_m[mocap::index(mocap::Segment::shank_l)]->z(), -0.45);
  EXPECT_DOUBLE_EQ(f->body.limits.joint[mocap::index(mocap::Segment::forearm_r)].b_min_deg, -170);
  auto g = parse("[body]\nmodel = \"" + body + "\"\nheight_m = 1.70\n", errs);
  ASSERT_TRUE(g) << errs.to_string();
  EXPECT_DOUBLE_EQ(g->body.model.height_m, 1.70);  // the inline height wins
  // The shipped files are valid.
  auto shipped = parse("[body]\nmodel = \"" MOCAP_SOURCE_DIR
                       "/config/body/default.toml\"\n"
                       "joint_limits = \"" MOCAP_SOURCE_DIR "/config/body/joint_limits.toml\"\n",
                       errs);
  EXPECT_TRUE(shipped) << errs.to_string();
  std::filesystem::remove(body);
  std::filesystem::remove(limits);
}

TEST(Config, BodyErrorsNameTheirFileAndLine) {
  ConfigErrors errs;
  // Inline: unknown segment at line 3 of the daemon's file.
  EXPECT_FALSE(parse(
      "[body]\nheight_m = 1.7\n[body.segment.forarm_l]\njoint_offset_m = [0, 0, -1]\n", errs));
  ASSERT_EQ(errs.errors.size(), 1u) << errs.to_string();
  EXPECT_EQ(errs.errors[0].file, "rig.toml");
  EXPECT_EQ(errs.errors[0].line, 3);
  EXPECT_NE(errs.to_string().find("unknown segment 'forarm_l'"), std::string::npos)
      << errs.to_string();
  // Inline joint limit that excludes the N-pose.
  errs = {};
  EXPECT_FALSE(parse("[body.joint.knee_l]\nb_deg = [10, 150]\n", errs));
  ASSERT_EQ(errs.errors.size(), 1u) << errs.to_string();
  EXPECT_EQ(errs.errors[0].line, 2);
  EXPECT_NE(errs.to_string().find("min <= 0 <= max"), std::string::npos) << errs.to_string();
  // An included file's error names that file's line and the including key.
  const std::string body =
      write_file("bad-body.toml", "height_m = 1.8\n\n[segment.head]\nend_offset_m = [0, 0]\n");
  errs = {};
  EXPECT_FALSE(parse("[body]\n\nmodel = \"" + body + "\"\n", errs));
  ASSERT_EQ(errs.errors.size(), 1u) << errs.to_string();
  EXPECT_EQ(errs.errors[0].file, body);
  EXPECT_EQ(errs.errors[0].line, 4);
  EXPECT_NE(errs.to_string().find("end_offset_m must be an array of 3 numbers"), std::string::npos)
      << errs.to_string();
  EXPECT_NE(errs.to_string().find("included by rig.toml:3 body.model"), std::string::npos)
      << errs.to_string();
  std::filesystem::remove(body);
  // Missing files and a height out of range.
  errs = {};
  EXPECT_FALSE(
      parse("[body]\njoint_limits = \"/nonexistent/limits.toml\"\nheight_m = 3.5\n", errs));
  ASSERT_EQ(errs.errors.size(), 2u) << errs.to_string();
  EXPECT_NE(errs.to_string().find(
                "rig.toml:2:16: body.joint_limits: /nonexistent/limits.toml: cannot open"),
            std::string::npos)
      << errs.to_string();
  EXPECT_NE(errs.to_string().find("rig.toml:3"), std::string::npos) << errs.to_string();
  // A device or a directory is refused, not read forever.
  errs = {};
  EXPECT_FALSE(parse("[body]\nmodel = \"/dev/zero\"\njoint_limits = \"/tmp\"\n", errs));
  ASSERT_EQ(errs.errors.size(), 2u) << errs.to_string();
  EXPECT_NE(errs.to_string().find("/dev/zero: cannot open body config (not a regular file)"),
            std::string::npos)
      << errs.to_string();
}

TEST(Config, VrchatOutputTrackersHeadAndHeight) {
  ConfigErrors errs;
  auto c = parse(
      "[outputs.vrchat]\nenabled = true\nhost = \"192.168.1.40\"\nport = 9001\n"
      "trackers = [\"pelvis\", \"\", \"foot_l\", \"foot_r\"]\nhead = false\nheight_m = 1.62\n",
      errs);
  ASSERT_TRUE(c) << errs.to_string();
  const auto& v = c->outputs.vrchat;
  EXPECT_TRUE(v.enabled);
  EXPECT_EQ(v.host, "192.168.1.40");
  EXPECT_EQ(v.port, 9001);
  EXPECT_EQ(v.trackers, (std::vector<std::string>{"pelvis", "", "foot_l", "foot_r"}));
  EXPECT_FALSE(v.head);
  EXPECT_DOUBLE_EQ(v.height_m, 1.62);
  const std::string printed = config_to_toml(*c);
  auto c2 = parse_config(printed, "printed", {}, errs);
  ASSERT_TRUE(c2) << errs.to_string() << printed;
  EXPECT_EQ(c2->outputs.vrchat.trackers, v.trackers);
  EXPECT_EQ(c2->outputs.vrchat.port, 9001);

  const Config defaults;
  EXPECT_FALSE(defaults.outputs.vrchat.enabled);
  EXPECT_EQ(defaults.outputs.vrchat.port, 9000);
  EXPECT_EQ(defaults.outputs.vrchat.trackers.size(), 8u);

  ConfigErrors bad;
  EXPECT_FALSE(
      parse("[outputs.vrchat]\ntrackers = [\"pelvis\", \"shank_left\"]\nhost = \"x\"\n"
            "height_m = 4\n",
            bad));
  const std::string all = bad.to_string();
  EXPECT_NE(all.find("outputs.vrchat.trackers: 'shank_left' is not a segment name (did you "
                     "mean 'shank_l'?)"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("outputs.vrchat.host"), std::string::npos) << all;
  EXPECT_NE(all.find("outputs.vrchat.height_m: 4 is out of range"), std::string::npos) << all;
}

TEST(ConfigLimits, SizeErrorCountAndMessageLengthAreBounded) {
  ConfigErrors errors;
  EXPECT_FALSE(parse_config(std::string(kMaxConfigBytes + 1, '#'), "big.toml", {}, errors));
  ASSERT_EQ(errors.errors.size(), 1u);
  EXPECT_NE(errors.errors[0].message.find("1 MiB"), std::string::npos);
  std::string many;
  for (int i = 0; i < 500; ++i)
    many += "bogus_" + std::to_string(i) + " = 1\n";
  errors = {};
  EXPECT_FALSE(parse_config(many, "many.toml", {}, errors));
  EXPECT_EQ(errors.errors.size(), kMaxConfigErrors + 1);
  EXPECT_NE(errors.errors.back().message.find("stopped checking"), std::string::npos);
  errors = {};
  EXPECT_FALSE(parse_config("[daemon]\nlog_level = \"" + std::string(100000, 'x') + "\"\n",
                            "long.toml", {}, errors));
  ASSERT_EQ(errors.errors.size(), 1u);
  EXPECT_LT(errors.errors[0].to_string().size(), 500u);
  EXPECT_NE(errors.errors[0].to_string().find("trace, debug"), std::string::npos);
}

// Issue 22 item 10: UTF-8 in comments and strings loads (config, body and limits files) and the
// names survive --print-config; invalid UTF-8, and non-ASCII outside strings and comments (where
// toml++ 3.3 has undefined behaviour), are refused with file:line:column.
TEST(Config, Utf8NamesAndCommentsLoadAndRoundTrip) {
  const std::string body = write_file("body-utf8.toml",
                                      "# mod\xC3\xA8le du corps \xE2\x80\x94 Jos\xC3\xA9\n"
                                      "height_m = 1.71 # taille mesur\xC3\xA9"
                                      "e\n");
  const std::string limits = write_file(
      "limits-utf8.toml", "# genou gauche\n[joint.elbow_r] # coude\nb_deg = [-170, 0]\n");
  const std::string text =
      "# Rig de Jos\xC3\xA9 \xE2\x80\x94 capteurs \xC3\xA0 l'\xC3\xA9paule\n"
      "[[sensor]]\n"
      "name = \"Jos\xC3\xA9\" # \xC3\xA9tiquette\n"
      "driver = \"witmotion\"\n"
      "port = \"/dev/ttyUSB0\"\n"
      "segment = \"torso\"\n"
      "[[sensor]]\n"
      "name = 'bassin-\xE2\x82\xAC' # capteur du bassin\n"
      "driver = \"witmotion\"\n"
      "port = \"/dev/serial/by-id/capteur du bassin \xC3\xA9\"\n"
      "segment = \"pelvis\"\n"
      "[body]\nmodel = \"" +
      body + "\"\njoint_limits = \"" + limits + "\"\n";
  ConfigErrors errs;
  auto c = parse(text, errs);
  ASSERT_TRUE(c) << errs.to_string();
  ASSERT_EQ(c->sensors.size(), 2u);
  EXPECT_EQ(c->sensors[0].name, "Jos\xC3\xA9");
  EXPECT_EQ(c->sensors[1].name, "bassin-\xE2\x82\xAC");
  EXPECT_DOUBLE_EQ(c->body.model.height_m, 1.71);
  // --print-config prints config_to_toml; it parses back with the same names.
  const std::string printed = config_to_toml(*c);
  EXPECT_NE(printed.find("Jos\xC3\xA9"), std::string::npos) << printed;
  auto c2 = parse_config(printed, "printed", {}, errs);
  ASSERT_TRUE(c2) << errs.to_string() << printed;
  EXPECT_EQ(c2->sensors[0].name, "Jos\xC3\xA9");
  EXPECT_EQ(c2->sensors[1].name, "bassin-\xE2\x82\xAC");
  EXPECT_EQ(c2->sensors[1].port, "/dev/serial/by-id/capteur du bassin \xC3\xA9");
  // --set addresses a sensor by its UTF-8 name and takes a UTF-8 value (bare or quoted).
  auto c3 =
      parse(text, errs, {"sensor.Jos\xC3\xA9.port=/dev/pts/\xC3\xA9", "daemon.log_level=info"});
  ASSERT_TRUE(c3) << errs.to_string();
  EXPECT_EQ(c3->sensors[0].port, "/dev/pts/\xC3\xA9");
  std::filesystem::remove(body);
  std::filesystem::remove(limits);
}

TEST(Config, InvalidUtf8IsRefusedWithItsPosition) {
  struct Case {
    std::string text;
    int line, column;
    std::string what;
  };
  const Case cases[] = {
      {"[pipeline]\n# ok \xC3\xA9\nrate_hz = 200 # \xFF\n", 3, 17, "invalid UTF-8 lead byte"},
      {"[[sensor]]\nname = \"Jos\xC3\"\n", 2, 12, "invalid UTF-8 continuation byte"},
      {"a = 1\n\n# \xC0\xAF\n", 3, 3, "overlong UTF-8 sequence"},
      {"# x\nname = \"\xED\xA0\x80\"\n", 2, 9, "UTF-8 encoded surrogate"},
      {"[pipeline]\nrate_hz = 200\xCF\x8F\n", 2, 14,
       "non-ASCII character outside a string or comment"},
  };
  for (const auto& c : cases) {
    ConfigErrors errs;
    EXPECT_FALSE(parse(c.text, errs)) << c.what;
    ASSERT_EQ(errs.errors.size(), 1u) << c.what;
    EXPECT_EQ(errs.errors[0].to_string(),
              "rig.toml:" + std::to_string(c.line) + ":" + std::to_string(c.column) + ": " + c.what)
        << c.what;
  }
  // A body file with invalid UTF-8 names that file and position.
  const std::string body = write_file("body-bad-utf8.toml", "height_m = 1.8\n# caf\xC3\n");
  ConfigErrors errs;
  EXPECT_FALSE(parse("[body]\nmodel = \"" + body + "\"\n", errs));
  EXPECT_NE(errs.to_string().find(body), std::string::npos) << errs.to_string();
  EXPECT_NE(errs.to_string().find("line 2, column 6"), std::string::npos) << errs.to_string();
  std::filesystem::remove(body);
}

// toml++ 3.3's is_non_ascii_horizontal_whitespace (unicode_autogenerated.h) reaches
// TOML_UNREACHABLE for code points such as U+03CF; it runs only outside strings and comments.
// Code points in comments, strings (basic, literal, multi-line) and quoted keys go through the
// loader without reaching it (the sanitizer build turns an unreachable into a crash), and a
// non-ASCII code point outside them never reaches toml++.
TEST(Config, NonAsciiCodePointsInStringsAndCommentsParse) {
  auto utf8 = [](uint32_t cp) {
    std::string s;
    if (cp < 0x800) {
      s += static_cast<char>(0xC0 | (cp >> 6));
    } else if (cp < 0x10000) {
      s += static_cast<char>(0xE0 | (cp >> 12));
      s += static_cast<char>(0x80 | ((cp >> 6) & 63));
    } else {
      s += static_cast<char>(0xF0 | (cp >> 18));
      s += static_cast<char>(0x80 | ((cp >> 12) & 63));
      s += static_cast<char>(0x80 | ((cp >> 6) & 63));
    }
    return s + static_cast<char>(0x80 | (cp & 63));
  };
  int checked = 0;
  for (uint32_t cp = 0x80; cp <= 0x10FFFF; cp += cp < 0x3100 ? 1 : 97) {
    if (cp >= 0xD800 && cp <= 0xDFFF) continue;
    const std::string c = utf8(cp);
    const std::string text = "# " + c + "\n[daemon] # " + c + "\nlog_level = \"" + c +
                             "\"\n[demo]\nmotion = '" + c + "'\n\"" + c + "\" = \"\"\"" + c +
                             "\n\"\"\"\n";
    ConfigErrors errs;
    EXPECT_FALSE(parse(text, errs)) << cp;  // the values are wrong, the text is fine
    ASSERT_FALSE(errs.errors.empty());
    // Parsed: every error is a key's (log_level, motion, the unknown key), none a syntax error.
    for (const auto& e : errs.errors)
      EXPECT_FALSE(e.key.empty()) << std::hex << cp << ": " << errs.to_string();
    errs = {};
    EXPECT_FALSE(parse("a = 1\nb = 2" + c + "\n", errs));
    ASSERT_EQ(errs.errors.size(), 1u);
    EXPECT_EQ(errs.errors[0].message, "non-ASCII character outside a string or comment");
    ++checked;
  }
  EXPECT_GT(checked, 20000);
}
