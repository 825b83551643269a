// SlimeVR trackers: the pure parser on the firmware's packets (and bundles, damaged and unknown
// ones), the decoder's mapping by MAC + sensor id, and the whole path over real UDP: simulated
// tracker boards handshake with the live device, stream, and ask for a reset.
#include <gtest/gtest.h>

#include <atomic>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/devsim/sim_slimevr.hpp"
#include "mocap/drivers/slimevr.hpp"

namespace mocap {
namespace {

namespace sv = slimevr;

std::vector<uint8_t> record(const std::vector<uint8_t>& datagram, uint32_t ip = 0x7f000001,
                            uint16_t port = 40000) {
  std::vector<uint8_t> r = {static_cast<uint8_t>(ip >> 24),  static_cast<uint8_t>(ip >> 16),
                            static_cast<uint8_t>(ip >> 8),   static_cast<uint8_t>(ip),
                            static_cast<uint8_t>(port >> 8), static_cast<uint8_t>(port)};
  r.insert(r.end(), datagram.begin(), datagram.end());
  return r;
}

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
  DeviceSpec spec;
  spec.name = "slime";
  spec.protocol = "slimevr";
  spec.options["trackers"] = "02:5E:00:00:00:01/1=7;02:5E:00:00:00:02/0=3@-y,x,z";
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  std::vector<uint8_t> d;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY()));
  // Data before any handshake: the board is unknown, nothing is emitted.
  slime_sim::rotation(1, 1, q, d);
  dec->feed(record(d), 1'000'000, sink);
  EXPECT_EQ(sink.count(), 0u);
  d.clear();
  slime_sim::handshake(mac_of("02:5E:00:00:00:01"), d);
  dec->feed(record(d), 2'000'000, sink);
  for (uint64_t n : {1, 2}) {
    d.clear();
    slime_sim::acceleration(2 * n, 1, Eigen::Vector3d(1, 0, 0), d);
    dec->feed(record(d), 3'000'000 + n, sink);
    d.clear();
    slime_sim::rotation(2 * n + 1, 1, q, d);
    dec->feed(record(d), 4'000'000 + n, sink);
  }
  // Sensor 0 of this board is not in the rig; a stale (reordered) packet number is dropped.
  d.clear();
  slime_sim::rotation(9, 0, q, d);
  dec->feed(record(d), 5'000'000, sink);
  d.clear();
  slime_sim::rotation(4, 1, q, d);
  dec->feed(record(d), 6'000'000, sink);
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

struct ResetSink : test::CollectSink {
  void on_reset_request(uint16_t device_index, ResetRequest r) override {
    last_index = device_index;
    last = static_cast<int>(r);
    ++resets;
  }
  std::atomic<int> resets{0}, last{-1}, last_index{-1};
};

TEST(SlimeVrDevice, UnmodifiedTrackerLogicConnectsOverRealUdpAndStreams) {
  const int port = test::free_loopback_port(SOCK_DGRAM);
  DeviceSpec spec;
  spec.name = "slimevr";
  spec.protocol = "slimevr";
  spec.port = "udp:127.0.0.1:" + std::to_string(port);
  spec.options["trackers"] = "02:5E:00:00:00:01/0=0;02:5E:00:00:00:01/1=1;02:5E:00:00:00:02/0=2";
  auto dev = make_device(spec, Logger(test::g_log_sink, "test"));
  ResetSink sink;
  dev->start(sink);
  SimSlimeOptions a;
  a.server = "127.0.0.1:" + std::to_string(port);
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

}  // namespace
}  // namespace mocap
