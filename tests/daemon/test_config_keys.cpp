// The configuration's key tables: typed filter keys bound to FilterParams, enums read by name,
// an exact --print-config round trip (every example rig too), the --help key list, and
// docs/configuration.md's key reference equal to what `mocapd --print-config-reference` writes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "mocap/daemon/config.hpp"

using namespace mocap;
using namespace mocap::daemon;

namespace {

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Prints `c`, parses the text and prints it again: the two texts must be equal.
void expect_exact_round_trip(const Config& c, const std::string& what) {
  const std::string printed = config_to_toml(c);
  ConfigErrors errs;
  auto back = parse_config(printed, c.source, {}, errs);
  ASSERT_TRUE(back) << what << "\n" << errs.to_string() << printed;
  EXPECT_EQ(config_to_toml(*back), printed) << what;
}

}  // namespace

TEST(ConfigKeys, FilterKeysAreTypedFilterParamsMembers) {
  ConfigErrors errs;
  auto c = parse_config(
      "[filter]\ntau_mag_s = 12\nrest_bias_est = false\nheading_sigma_deg = "
      "0.1234567890123456789\n",
      "rig.toml", {}, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->filter.params.heading.tau_mag_s, 12.0);
  EXPECT_FALSE(c->filter.params.bias.rest_est);
  EXPECT_EQ(c->filter.params.heading.sigma_deg, 0.1234567890123456789);
  // Untouched members keep the filter's defaults.
  EXPECT_EQ(c->filter.params.inclination.tau_acc_s, FilterParams{}.inclination.tau_acc_s);
  // Printed: only the members that differ from the defaults, at full precision.
  const std::string printed = config_to_toml(*c);
  EXPECT_NE(printed.find("tau_mag_s = 12"), std::string::npos) << printed;
  EXPECT_EQ(printed.find("tau_acc_s"), std::string::npos) << printed;
  auto back = parse_config(printed, "printed", {}, errs);
  ASSERT_TRUE(back) << errs.to_string();
  EXPECT_EQ(back->filter.params.heading.sigma_deg, c->filter.params.heading.sigma_deg);
  // A boolean member takes a boolean, a number member a number; errors name the key.
  for (const char* bad : {"rest_bias_est = 1.5", "tau_mag_s = true", "tau_mag_s = \"12\""}) {
    ConfigErrors e;
    EXPECT_FALSE(parse_config(std::string("[filter]\n") + bad + "\n", "rig.toml", {}, e)) << bad;
    const std::string key = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(e.to_string().find("rig.toml:2:"), std::string::npos) << e.to_string();
    EXPECT_NE(e.to_string().find("filter." + key + ": expected"), std::string::npos)
        << e.to_string();
  }
  // --set reaches them as well.
  auto s = parse_config("", "rig.toml", {"filter.tau_mag_s=7.25"}, errs);
  ASSERT_TRUE(s) << errs.to_string();
  EXPECT_EQ(s->filter.params.heading.tau_mag_s, 7.25);
}

TEST(ConfigKeys, EnumsReadByName) {
  ConfigErrors errs;
  auto c = parse_config(
      "[daemon]\nlog_level = \"warn\"\n[calibration]\npose = \"tpose\"\nheading = "
      "\"mean_sensors\"\n[demo]\npath = \"direct\"\n",
      "rig.toml", {}, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->daemon.log_level, LogLevel::warn);
  EXPECT_EQ(c->calibration.pose, CalibrationPose::tpose);
  EXPECT_EQ(c->calibration.heading, HeadingSource::mean_sensors);
  EXPECT_EQ(c->demo.path, DemoPath::direct);
  // Only the listed names: a HeadingSource the calibration does not offer is refused.
  ConfigErrors e;
  EXPECT_FALSE(parse_config("[calibration]\nheading = \"arm_swing\"\n", "rig.toml", {}, e));
  EXPECT_NE(e.to_string().find("rig.toml:2:11: calibration.heading: 'arm_swing' is not one of "
                               "mount_normals, pelvis_sensor, mean_sensors"),
            std::string::npos)
      << e.to_string();
}

TEST(ConfigKeys, PrintConfigRoundTripIsExact) {
  ConfigErrors errs;
  auto c = parse_config(R"(
[pipeline]
rate_hz = 123.45678901234567
stale_after_ms = 0.1e3
[filter]
tau_mag_s = 3.3333333333333335
[body]
height_m = 1.7777777777777777
[calibration]
capture_s = 0.30000000000000004
heading = "pelvis_sensor"
pose = "tpose"
[outputs.vrchat]
trackers = ["pelvis", "", "foot_l"]
height_m = 1.6100000000000001
[demo]
seed = 9223372036854775807
path = "direct"
[[sensor]]
name = "a"
driver = "witmotion"
port = "/dev/x"
rate_hz = 99.999999999999986
gyr_scale = [1.0000000000000002, 0.99999999999999989, 1.1]
site_normal = [0.1, 0.2, 0.30000000000000004]
log_level = "debug"
[sensor.options]
gain = 0.1
[[sensor]]
name = "b"
driver = "xbus"
vid = 0x2639
pid = 0x0300
serial = "X1"
hid = true
)",
                        "rig.toml", {}, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->pipeline.rate_hz, 123.45678901234567);
  EXPECT_EQ(c->demo.seed, 9223372036854775807ull);
  EXPECT_EQ(c->sensors[0].options.at("gain"), "0.1");  // shortest exact text, not 6 digits
  expect_exact_round_trip(*c, "full");
  ConfigErrors e2;
  auto back = parse_config(config_to_toml(*c), "rig.toml", {}, e2);
  ASSERT_TRUE(back) << e2.to_string();
  EXPECT_EQ(back->pipeline.rate_hz, c->pipeline.rate_hz);
  EXPECT_EQ(back->body.model.height_m, c->body.model.height_m);
  EXPECT_EQ(back->calibration.capture_s, c->calibration.capture_s);
  EXPECT_EQ(back->outputs.vrchat.trackers, c->outputs.vrchat.trackers);
  EXPECT_EQ(back->sensors[0].gyr_scale, c->sensors[0].gyr_scale);
  EXPECT_EQ(back->sensors[0].site_normal, c->sensors[0].site_normal);
  EXPECT_EQ(back->sensors[0].log_level, LogLevel::debug);
  EXPECT_EQ(back->sensors[1].serial, "X1");
  EXPECT_TRUE(back->sensors[1].hid);
  EXPECT_EQ(back->filter.params.heading.tau_mag_s, 3.3333333333333335);
}

// A string holding ''' and a newline (toml++ would print it as a literal string that does not
// parse back) is printed as a basic string and comes back unchanged.
TEST(ConfigKeys, AnyStringRoundTrips) {
  ConfigErrors errs;
  const char* text = R"T([recording]
auto_start = """a'''b\n"c"\t\\"""
)T";
  auto c = parse_config(text, "rig.toml", {}, errs);
  ASSERT_TRUE(c) << errs.to_string();
  EXPECT_EQ(c->recording.auto_start, "a'''b\n\"c\"\t\\");
  expect_exact_round_trip(*c, "string");
}

// Every example rig loads and prints to a text that loads to the same configuration.
TEST(ConfigKeys, ExampleRigsRoundTrip) {
  const std::filesystem::path src = MOCAP_SOURCE_DIR;
  std::filesystem::current_path(src);  // body files are relative to the working directory
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(src / "config")) {
    if (e.path().extension() != ".toml") continue;
    ConfigErrors errs;
    auto c = load_config(e.path().string(), {}, errs, &default_validators());
    ASSERT_TRUE(c) << e.path() << "\n" << errs.to_string();
    expect_exact_round_trip(*c, e.path().string());
    ++n;
  }
  EXPECT_GE(n, 7);
}

TEST(ConfigKeys, HelpListsEveryKey) {
  const std::string s = config_key_summary();
  for (const char* k : {"  daemon: log_level control_socket", "  pipeline: rate_hz",
                        "  filter: use_mag", "outputs.vrchat: enabled host port trackers",
                        "sensor.NAME: name driver port vid pid", "gyr_scale log_level options"})
    EXPECT_NE(s.find(k), std::string::npos) << k << "\n" << s;
  EXPECT_EQ(s.find("enforce_limits"), std::string::npos);  // removed keys are not offered
}

// docs/configuration.md's key reference is generated: the text between its markers must be
// what `mocapd --print-config-reference` writes (scripts/update-config-doc rewrites it).
TEST(ConfigKeys, CommittedDocMatchesGeneratedReference) {
  const std::string doc =
      read_text(std::filesystem::path(MOCAP_SOURCE_DIR) / "docs" / "configuration.md");
  const std::string begin = "<!-- BEGIN generated: mocapd --print-config-reference -->\n";
  const std::string end = "<!-- END generated -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  const std::string committed = doc.substr(b + begin.size(), e - b - begin.size());
  EXPECT_EQ(committed, config_reference_markdown())
      << "docs/configuration.md is out of date: run scripts/update-config-doc";
  // Every key of the defaults' printed configuration is described there.
  std::istringstream printed(config_to_toml(Config{}));
  for (std::string line; std::getline(printed, line);) {
    const size_t eq = line.find(" = ");
    if (eq == std::string::npos || line[0] == '#') continue;
    EXPECT_NE(committed.find("| `" + line.substr(0, eq) + "` |"), std::string::npos) << line;
  }
}

// Every key the defaults print, set by --set to a few odd values: each either loads and prints
// back exactly, or is refused with an error naming the key (never a partial configuration).
TEST(ConfigKeys, EveryPrintedKeyRoundTripsOrIsRefusedByName) {
  std::vector<std::string> keys;
  std::istringstream printed(config_to_toml(Config{}));
  std::string section;
  for (std::string line; std::getline(printed, line);) {
    if (line.size() > 2 && line[0] == '[') section = line.substr(1, line.find(']') - 1);
    const size_t eq = line.find(" = ");
    if (eq != std::string::npos && line[0] != '#')
      keys.push_back(section + "." + line.substr(0, eq));
  }
  ASSERT_GT(keys.size(), 30u);
  // The filter's parameters are printed only when changed: two of them, one of each type.
  keys.insert(keys.end(), {"filter.tau_mag_s", "filter.rest_bias_est"});
  int loaded = 0;
  for (const std::string& key : keys) {
    for (const char* value : {"0", "1", "-1", "0.1", "1e300", "nan", "true", "\"x\"", "[1, 2, 3]",
                              "1.0000000000000002", "\"debug\"", "\"direct\"", "\"tpose\""}) {
      ConfigErrors errs;
      auto c = parse_config("", "rig.toml", {key + "=" + value}, errs);
      if (!c) {
        ASSERT_FALSE(errs.errors.empty()) << key << "=" << value;
        EXPECT_NE(errs.to_string().find(key), std::string::npos)
            << key << "=" << value << ": " << errs.to_string();
        continue;
      }
      ++loaded;
      expect_exact_round_trip(*c, key + "=" + value);
    }
  }
  EXPECT_GT(loaded, static_cast<int>(keys.size()));  // most keys take some of the values
}
