// SlimeVR trackers: the pure parser on the firmware's packets (and bundles, damaged and unknown
// ones), the decoder's mapping by MAC + sensor id, and the whole path over real UDP: simulated
// tracker boards handshake with the live device, stream, and ask for a reset.
#include <gtest/gtest.h>

#include <atomic>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/devsim/sim_slimevr.hpp"
#include "mocap/devsim/sim_transport.hpp"
#include "mocap/drivers/slimevr.hpp"
#include "mocap/drivers/slimevr_hid.hpp"
#include "slimevr_test_util.hpp"

namespace mocap {
namespace {

namespace sv = slimevr;

sv::Mac mac_of(const char* text) {
  sv::Mac m{};
  EXPECT_TRUE(sv::parse_mac(text, m));
  return m;
}

TEST(SlimeVrParser, HandshakeGivesBoardFirmwareAndMac) {
  std::vector<uint8_t> d;
  slime_sim::handshake(mac_of("02:5e:00:00:00:2a"), d);
  std::array<sv::Packet, 4> p;
  sv::Error err;
  ASSERT_EQ(sv::parse_datagram(d, p, err), 1u);
  EXPECT_EQ(err, sv::Error::kNone);
  EXPECT_EQ(p[0].type, sv::kHandshake);
  EXPECT_EQ(p[0].protocol_version, 22u);
  EXPECT_EQ(p[0].firmware_text(), "0.6.0-sim");
  ASSERT_TRUE(p[0].has_mac);
  EXPECT_EQ(sv::mac_string(p[0].mac), "02:5E:00:00:00:2A");
  // Old firmware stops after the firmware string: still a handshake, without a MAC.
  d.resize(12 + 7 * 4 + 1 + 9);
  ASSERT_EQ(sv::parse_datagram(d, p, err), 1u);
  EXPECT_FALSE(p[0].has_mac);
}

TEST(SlimeVrParser, RotationAccelerationAndBundles) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  std::vector<uint8_t> rot, acc;
  slime_sim::rotation(5, 1, q, rot);
  slime_sim::acceleration(6, 1, Eigen::Vector3d(0.5, -1, 2), acc);
  EXPECT_EQ(rot.size(), 31u);
  EXPECT_EQ(acc.size(), 25u);
  std::array<sv::Packet, 8> p;
  sv::Error err;
  ASSERT_EQ(sv::parse_datagram(rot, p, err), 1u);
  EXPECT_EQ(p[0].number, 5u);
  EXPECT_EQ(p[0].sensor_id, 1);
  EXPECT_NEAR(p[0].quat_xyzw[3], q.w(), 1e-6);
  EXPECT_NEAR(p[0].quat_xyzw[0], q.x(), 1e-6);
  // Bundle 100: [u16 len][u32 type + body] per entry, body without a packet number.
  std::vector<uint8_t> b = {0, 0, 0, 100, 0, 0, 0, 0, 0, 0, 0, 9};
  for (const auto* inner : {&rot, &acc}) {
    const std::size_t len = inner->size() - 8;  // type + body
    b.push_back(static_cast<uint8_t>(len >> 8));
    b.push_back(static_cast<uint8_t>(len));
    b.insert(b.end(), inner->begin(), inner->begin() + 4);
    b.insert(b.end(), inner->begin() + 12, inner->end());
  }
  ASSERT_EQ(sv::parse_datagram(b, p, err), 2u);
  EXPECT_EQ(err, sv::Error::kNone);
  EXPECT_EQ(p[0].type, sv::kRotationData);
  EXPECT_EQ(p[1].type, sv::kAccel);
  EXPECT_FLOAT_EQ(p[1].accel[2], 2.0f);
  EXPECT_EQ(p[1].sensor_id, 1);
  // Compact bundle 101: [u8 len][u8 type + body].
  std::vector<uint8_t> c = {0, 0, 0, 101, 0, 0, 0, 0, 0, 0, 0, 10};
  c.push_back(static_cast<uint8_t>(rot.size() - 12 + 1));
  c.push_back(sv::kRotationData);
  c.insert(c.end(), rot.begin() + 12, rot.end());
  ASSERT_EQ(sv::parse_datagram(c, p, err), 1u);
  EXPECT_EQ(p[0].type, sv::kRotationData);
  // A bundle entry longer than the datagram stops the bundle, keeping what came before.
  b.push_back(0xff), b.push_back(0xff);
  EXPECT_EQ(sv::parse_datagram(b, p, err), 2u);
  EXPECT_EQ(err, sv::Error::kBadBundle);
}

TEST(SlimeVrParser, DamagedAndUnknownPacketsAreRefusedWithAReason) {
  std::vector<uint8_t> rot;
  slime_sim::rotation(5, 0, Eigen::Quaterniond::Identity(), rot);
  std::array<sv::Packet, 2> p;
  sv::Error err;
  rot.resize(20);
  EXPECT_EQ(sv::parse_datagram(rot, p, err), 0u);
  EXPECT_EQ(err, sv::Error::kShort);
  const std::vector<uint8_t> unknown = {0, 0, 0, 77, 0, 0, 0, 0, 0, 0, 0, 1, 1, 2, 3};
  EXPECT_EQ(sv::parse_datagram(unknown, p, err), 0u);
  EXPECT_EQ(err, sv::Error::kUnknownType);
  EXPECT_STREQ(sv::error_text(err), "unknown packet type (skipped)");
  EXPECT_EQ(sv::parse_datagram(std::vector<uint8_t>{0, 0, 0}, p, err), 0u);
  EXPECT_EQ(err, sv::Error::kShort);
}

TEST(SlimeVrParser, ServerPackets) {
  std::array<uint8_t, sv::kHandshakeReplySize> hey{};
  sv::write_handshake_reply(hey);
  EXPECT_EQ(hey[0], 3);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&hey[1]), 12), "Hey OVR =D 5");
  EXPECT_EQ(hey[13], 0);
  std::array<uint8_t, 6> ack{};
  sv::write_sensor_info_ack(ack, 2, 1);
  EXPECT_EQ(ack, (std::array<uint8_t, 6>{0, 0, 0, 15, 2, 1}));
  std::array<uint8_t, 16> ping{};
  sv::write_ping(ping, 0, 0x01020304);
  EXPECT_EQ(ping[3], 10);
  EXPECT_EQ(ping[15], 4);
}

TEST(SlimeVrDecoder, MapsMacAndSensorIdToTheRigSensorAndCarriesTheOrientation) {
  auto dec = test::slimevr_decoder("slimevr", "02:5E:00:00:00:01/1=7;02:5E:00:00:00:02/0=3@-y,x,z");
  test::CollectSink sink;
  std::vector<uint8_t> d;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
  // Data before any handshake: the board is unknown, nothing is emitted.
  slime_sim::rotation(1, 1, q, d);
  dec->feed(test::slimevr_record(d), 1'000'000, sink);
  EXPECT_EQ(sink.count(), 0u);
  d.clear();
  slime_sim::handshake(mac_of("02:5E:00:00:00:01"), d);
  dec->feed(test::slimevr_record(d), 2'000'000, sink);
  for (uint64_t n : {1, 2}) {
    d.clear();
    slime_sim::acceleration(2 * n, 1, Eigen::Vector3d(1, 0, 0), d);
    dec->feed(test::slimevr_record(d), 3'000'000 + n, sink);
    d.clear();
    slime_sim::rotation(2 * n + 1, 1, q, d);
    dec->feed(test::slimevr_record(d), 4'000'000 + n, sink);
  }
  // Sensor 0 of this board is not in the rig; a stale (reordered) packet number is dropped.
  d.clear();
  slime_sim::rotation(9, 0, q, d);
  dec->feed(test::slimevr_record(d), 5'000'000, sink);
  d.clear();
  slime_sim::rotation(4, 1, q, d);
  dec->feed(test::slimevr_record(d), 6'000'000, sink);
  const auto s = sink.snapshot();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].sensor_id, 7);
  EXPECT_TRUE(s[0].has(kFieldQuat));
  EXPECT_FALSE(s[0].has(kFieldGyr));
  EXPECT_LT(s[0].q_device_sensor.angularDistance(q), 1e-6);
  // Specific force: the linear acceleration plus gravity seen in the sensor frame.
  const Eigen::Vector3d f =
      Eigen::Vector3d(1, 0, 0) + q.conjugate() * Eigen::Vector3d(0, 0, 9.80665);
  EXPECT_LT((s[1].acc_m_s2 - f).norm(), 1e-5);
  EXPECT_EQ(dec->stats().dropped_samples, 1u);
  // Each sample's number is its datagram's packet number (frames show it: a client can tell
  // which datagram a frame answers).
  EXPECT_EQ(s[0].seq, 3u);
  EXPECT_EQ(s[1].seq, 5u);
}

// A tracker that reboots starts its orientation in a new frame: its first sample after says so
// (kFlagDeviceRestarted; the body tracker then finds its heading again): its packet count
// begins again, from the same address or another. A handshake recorded again in a take (the
// device re-records each board's every 250 ms) is none, nor is a board back after a silence
// with its count going on (it reconnected: its fusion ran on).
TEST(SlimeVrDecoder, ATrackerThatRebootedSaysSoInItsFirstSample) {
  auto dec = test::slimevr_decoder("slimevr", "02:5E:00:00:00:01/0=0");
  test::CollectSink sink;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  int64_t t_ns = 0;
  const auto send = [&](const std::vector<uint8_t>& d, uint16_t port = 40000) {
    dec->feed(test::slimevr_record(d, 0x7f000001, port), t_ns += 10'000'000, sink);
  };
  const auto rotations = [&](uint64_t from, uint64_t to, uint16_t port = 40000) {
    for (uint64_t n = from; n <= to; ++n) {
      std::vector<uint8_t> d;
      slime_sim::rotation(n, 0, q, d);
      send(d, port);
    }
  };
  std::vector<uint8_t> hello;
  slime_sim::handshake(mac_of("02:5E:00:00:00:01"), hello);
  send(hello);
  rotations(1, 5);
  send(hello);  // recorded again: the count goes on
  rotations(6, 8);
  send(hello);  // rebooted: the count begins again
  rotations(1, 3);
  t_ns += 4'000'000'000;
  send(hello, 40001);  // back after a silence from another port, the count going on
  rotations(4, 5, 40001);
  send(hello, 40002);  // rebooted, from another port
  rotations(1, 2, 40002);
  const auto s = sink.snapshot();
  ASSERT_EQ(s.size(), 15u);
  for (std::size_t i = 0; i < s.size(); ++i)
    EXPECT_EQ((s[i].flags & kFlagDeviceRestarted) != 0, i == 8 || i == 13) << "sample " << i;
}

TEST(SlimeVrDecoder, ASensorWithoutAMacIsRefusedWithAClearError) {
  DeviceSpec spec;
  spec.name = "hip";
  spec.protocol = "slimevr";
  try {
    make_decoder(spec);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("options.mac"), std::string::npos) << e.what();
  }
  spec.options["mac"] = "02:5E:00:00:00";
  EXPECT_THROW(make_decoder(spec), std::invalid_argument);
  spec.options["trackers"] = "02:5E:00:00:00:01=3";
  EXPECT_THROW(make_decoder(spec), std::invalid_argument);
  spec.options.erase("trackers");
  spec.options["mac"] = "02:5E:00:00:00:01";
  EXPECT_NO_THROW(make_decoder(spec));
  spec.port = "/dev/ttyUSB0";  // trackers talk UDP
  EXPECT_THROW(make_decoder(spec), std::invalid_argument);
}

/// A SlimeVR server device's spec on a loopback UDP port that was free a moment ago; `server`
/// becomes that address for the simulated trackers.
DeviceSpec loopback_server_spec(std::string& server) {
  server = "127.0.0.1:" + std::to_string(test::free_loopback_port(SOCK_DGRAM));
  DeviceSpec spec;
  spec.name = "slimevr";
  spec.protocol = "slimevr";
  spec.port = "udp:" + server;
  return spec;
}

struct ResetSink : test::CollectSink {
  void on_reset_request(uint16_t device_index, ResetRequest r) override {
    last_index = device_index;
    last = static_cast<int>(r);
    ++resets;
  }
  std::atomic<int> resets{0}, last{-1}, last_index{-1};
};

TEST(SlimeVrDevice, UnmodifiedTrackerLogicConnectsOverRealUdpAndStreams) {
  std::string server;
  DeviceSpec spec = loopback_server_spec(server);
  spec.options["trackers"] = "02:5E:00:00:00:01/0=0;02:5E:00:00:00:01/1=1;02:5E:00:00:00:02/0=2";
  auto dev = make_device(spec, Logger(test::g_log_sink, "test"));
  ResetSink sink;
  dev->start(sink);
  SimSlimeOptions a;
  a.server = server;
  a.mac = "02:5E:00:00:00:01";
  a.sensors = 2;
  SimSlimeOptions b = a;
  b.mac = "02:5E:00:00:00:02";
  b.sensors = 1;
  SimSlimeTracker ta(a), tb(b);
  ta.start();
  tb.start();
  const auto per_sensor = [&](int id) {
    int n = 0;
    for (const auto& s : sink.snapshot())
      n += s.sensor_id == id;
    return n;
  };
  ASSERT_TRUE(sink.wait_for(
      [&] { return per_sensor(0) > 20 && per_sensor(1) > 20 && per_sensor(2) > 20; }));
  EXPECT_TRUE(ta.connected());
  EXPECT_TRUE(tb.connected());
  // The samples carry the tracker's own orientation: the truth the simulator sent.
  // (The firmware sends acceleration after rotation: only each sensor's first sample has none.)
  std::size_t with_acc = 0;
  const auto all = sink.snapshot();
  for (const auto& s : all) {
    ASSERT_TRUE(s.has(kFieldQuat));
    with_acc += s.has(kFieldAcc);
    EXPECT_NEAR(s.q_device_sensor.norm(), 1.0, 1e-9);
  }
  EXPECT_GE(with_acc + 3, all.size());
  tb.press(sv::kResetYaw);
  ASSERT_TRUE(sink.wait_for([&] { return sink.resets > 0; }));
  EXPECT_EQ(sink.last, static_cast<int>(ResetRequest::heading));
  EXPECT_EQ(sink.last_index, 2);
  // A board that stops talking is reported disconnected (3 s), then reconnects when it returns.
  tb.stop();
  ASSERT_TRUE(sink.wait_for([&] {
    for (const auto& e : sink.events_snapshot())
      if (!e.connected && e.reason.find("02:5E:00:00:00:02") != std::string::npos) return true;
    return false;
  }));
  ta.stop();
  dev->stop();
  EXPECT_GT(dev->stats().decoder.frames, 60u);
}

// A resting tracker (the firmware sends only changed rotations) still answers the server: its
// orientation is repeated (flagged interpolated) so the rig never takes it for stale.
TEST(SlimeVrDevice, AQuietRestingTrackerKeepsItsOrientationAlive) {
  std::string server;
  DeviceSpec spec = loopback_server_spec(server);
  spec.options["mac"] = "02:5E:00:00:00:09";
  auto dev = make_device(spec, Logger(test::g_log_sink, "test"));
  test::CollectSink sink;
  dev->start(sink);
  SimSlimeOptions o;
  o.server = server;
  o.mac = "02:5E:00:00:00:09";
  o.motion = "static";
  o.optimize_updates = true;
  SimSlimeTracker t(o);
  t.start();
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 15; }));  // about 1.5 s of rest
  t.stop();
  dev->stop();
  const auto all = sink.snapshot();
  EXPECT_FALSE(all.front().flags & kFlagInterpolated);  // the one rotation sent
  for (std::size_t i = 1; i < all.size(); ++i) {
    EXPECT_TRUE(all[i].flags & kFlagInterpolated);
    EXPECT_LT(all[i].q_device_sensor.angularDistance(all.front().q_device_sensor), 1e-9);
    EXPECT_LT(all[i].t_host_ns - all[i - 1].t_host_ns, 250'000'000);  // never stale
  }
}

}  // namespace
}  // namespace mocap

namespace mocap {
namespace {

std::vector<uint8_t> hid_report(ProtocolEncoder& enc, const Motion& m, int64_t t_ns) {
  std::vector<uint8_t> r;
  enc.encode(m.at(t_ns), r);
  return r;
}

TEST(SlimeVrHid, ParsesPacketsWithOrWithoutAReportIdAndSkipsPadding) {
  std::vector<uint8_t> r(64, 0);
  r[0] = slimevr_hid::kQuatAccel;
  r[1] = 3;
  r[8] = 0xff, r[9] = 0x7f;    // w = 32767 / 32768
  r[14] = 0x80, r[15] = 0x04;  // az = 1152 / 128 = 9 m/s^2
  r[16] = slimevr_hid::kCompactQuatAccel;
  r[17] = 4;
  const uint32_t zero = 512u | 1024u << 10 | 1024u << 21;  // exponential map (0, 0, 0)
  for (int j = 0; j < 4; ++j)
    r[21 + j] = static_cast<uint8_t>(zero >> (8 * j));
  r[32] = 9;  // a type whose layout is not known: skipped
  std::array<slimevr_hid::Packet, 8> p;
  ASSERT_EQ(slimevr_hid::parse_report(r, p), 2u);
  EXPECT_EQ(p[0].id, 3);
  EXPECT_NEAR(p[0].quat_xyzw[3], 1.0, 1e-4);
  EXPECT_DOUBLE_EQ(p[0].accel_m_s2[2], 9.0);
  EXPECT_EQ(p[1].id, 4);
  EXPECT_NEAR(p[1].quat_xyzw[3], 1.0, 1e-3);
  std::vector<uint8_t> with_id = {0x01};
  with_id.insert(with_id.end(), r.begin(), r.end());
  EXPECT_EQ(slimevr_hid::parse_report(with_id, p), 2u);
}

TEST(SlimeVrHid, TrackersAppearByAddressStreamAndLeave) {
  auto dec = test::slimevr_dongle_decoder();
  auto two = make_encoder("slimevr_hid", {.rate_hz = 100, .options = {{"trackers", "2"}}});
  auto one = make_encoder("slimevr_hid", {.rate_hz = 100, .options = {{"trackers", "1"}}});
  auto motion = make_motion("rotate");
  test::CollectSink sink;
  int64_t t = 1'000'000'000;
  for (int i = 0; i < 50; ++i, t += 10'000'000)
    dec->feed(hid_report(*two, *motion, t), t, sink);
  int n4 = 0, n5 = 0;
  for (const auto& s : sink.snapshot()) {
    n4 += s.sensor_id == 4, n5 += s.sensor_id == 5;
    ASSERT_TRUE(s.has(kFieldQuat));
    ASSERT_FALSE(s.has(kFieldGyr));
    const auto truth = motion->at(s.t_host_ns).q_device_sensor;
    EXPECT_LT(s.q_device_sensor.angularDistance(truth), 1e-3);  // Q15
  }
  EXPECT_GE(n4, 48);
  EXPECT_GE(n5, 47);  // its first register packet comes in the second report
  // Tracker 2 goes away; the receiver keeps reporting tracker 1: after 3 s tracker 2 has left.
  for (int i = 0; i < 400; ++i, t += 10'000'000)
    dec->feed(hid_report(*one, *motion, t), t, sink);
  int appeared = 0, left = 0;
  for (const auto& e : sink.events_snapshot()) {
    appeared += e.connected && e.reason.find("appeared") != std::string::npos;
    left += !e.connected && e.reason == "tracker 02:5E:00:00:00:A1 left the receiver";
  }
  EXPECT_EQ(appeared, 2);
  EXPECT_EQ(left, 1);
}

TEST(SlimeVrHid, TheLiveDeviceRunsOnASimulatedReceiver) {
  DeviceSpec spec;
  spec.name = "dongle";
  spec.protocol = "slimevr_hid";
  spec.options["mac"] = "02:5E:00:00:00:A0";
  spec.first_sensor_id = 2;
  auto dev = make_device_with_transport(spec, Logger(test::g_log_sink, "test"), [](std::string&) {
    return std::make_unique<SimReportTransport>(
        make_encoder("slimevr_hid", {.rate_hz = 200, .options = {}}), make_motion("rotate"));
  });
  test::CollectSink sink;
  dev->start(sink);
  EXPECT_TRUE(sink.wait_for([&] { return sink.count() > 50; }));
  dev->stop();
  for (const auto& s : sink.snapshot())
    EXPECT_EQ(s.sensor_id, 2);
}

}  // namespace
}  // namespace mocap
