// What SlimeVR trackers report about themselves: the HID receiver's packet types 0-7 in the byte
// layouts SlimeVR-Tracker-nRF writes (connection.c) and its receiver forwards (RSSI in byte 15),
// decoded into battery, voltage, temperature, signal, runtime, packet loss and identity; the UDP
// packets 12 (battery), 19 (signal strength), 20 (temperature) and the handshake's board, IMU,
// MCU and firmware; each decoder reporting a sensor's telemetry when it changes.
#include <gtest/gtest.h>

#include <cmath>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_slimevr.hpp"
#include "mocap/drivers/slimevr.hpp"
#include "mocap/drivers/slimevr_hid.hpp"
#include "slimevr_test_util.hpp"

namespace mocap {
namespace {

namespace sh = slimevr_hid;
namespace sv = slimevr;

using Bytes = std::array<uint8_t, 16>;

// The exponential map (0, 0, 0) (identity) quantised to 10/11/11 bits, little-endian.
constexpr uint8_t kQIdentity[4] = {0x00, 0x02, 0x10, 0x80};  // 512 | 1024 << 10 | 1024 << 21

// Tracker 1 as its firmware writes it: 80 % (0x80 | 80), 3.70 V ((370 - 245) = 125), 25.0 degC
// ((25 - 25) * 2 + 128.5 truncated = 128), the receiver's RSSI magnitude in byte 15.
const Bytes kInfo = {0, 1, 0xD0, 125, 128, 9, 12, 0, 11, 1, 0x6E, 0x0A, 0, 6, 2, 60};
// fw_date 0x0A6E = (2025 - 2020) << 9 | 3 << 5 | 14; version 0.6.2; board 9, MCU 12, IMU 11.
const Bytes kCompact = {
    2, 1, 0xD0, 125,  128, kQIdentity[0], kQIdentity[1], kQIdentity[2], kQIdentity[3], 0, 0,
    0, 0, 0x80, 0x04, 58};  // az = 9 m/s^2
// Status: server status OK, tracker status 0, 200 received, 10 lost, 50 windows hit, 2 missed.
const Bytes kStatusPacket = {3, 1, 1, 0, 200, 10, 50, 2, 0, 0, 0, 0, 0, 0, 0, 55};
// Runtime: 3.6e9 us (one hour) of battery left, i64 little-endian.
const Bytes kRuntime = {5, 1, 0x00, 0xA4, 0x93, 0xD6, 0, 0, 0, 0, 0, 0, 0, 0, 0, 61};
// Button: single press, 1000 ms until sleep.
const Bytes kButton = {6, 1, 1, 0xE8, 0x03, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 62};
// Button (double press), 10 s until sleep, and the reduced quaternion + acceleration.
const Bytes kButtonQuat = {
    7, 1, 2,    0x10, 0x27, kQIdentity[0], kQIdentity[1], kQIdentity[2], kQIdentity[3], 0, 0,
    0, 0, 0x80, 0x04, 63};
// The receiver binds id 1 to address 02:5E:00:00:00:A0 (little-endian on the wire).
const Bytes kRegister = {255, 1, 0xA0, 0x00, 0x00, 0x00, 0x5E, 0x02, 0, 0, 0, 0, 0, 0, 0, 0};

sh::Packet parse(const Bytes& b) {
  sh::Packet p;
  EXPECT_TRUE(sh::parse_packet(std::span<const uint8_t, 16>(b), p)) << int{b[0]};
  return p;
}

std::vector<uint8_t> report(std::initializer_list<const Bytes*> packets) {
  std::vector<uint8_t> r(64, 0);
  std::size_t at = 0;
  for (const Bytes* b : packets) {
    std::copy(b->begin(), b->end(), r.begin() + static_cast<std::ptrdiff_t>(at));
    at += 16;
  }
  return r;
}

/// The four telemetry figures every packet type with them carries.
void expect_telemetry(const sh::Packet& p, float battery, float volts, float celsius, float dbm) {
  EXPECT_FLOAT_EQ(p.battery_fraction, battery);
  EXPECT_FLOAT_EQ(p.battery_v, volts);
  EXPECT_FLOAT_EQ(p.temperature_c, celsius);
  EXPECT_FLOAT_EQ(p.rssi_dbm, dbm);
}

TEST(SlimeVrHidTelemetry, DeviceInfoGivesBatteryTemperatureIdentityAndSignal) {
  const sh::Packet p = parse(kInfo);
  expect_telemetry(p, 0.80f, 3.70f, 25.0f, -60.0f);
  EXPECT_EQ(p.board, 9);
  EXPECT_EQ(p.mcu, 12);
  EXPECT_EQ(p.imu, 11);
  EXPECT_EQ(p.mag, 1);
  ASSERT_TRUE(p.has_firmware);
  EXPECT_EQ(p.fw_year, 2025);
  EXPECT_EQ(p.fw_month, 3);
  EXPECT_EQ(p.fw_day, 14);
  EXPECT_EQ(p.fw_major, 0);
  EXPECT_EQ(p.fw_minor, 6);
  EXPECT_EQ(p.fw_patch, 2);
  EXPECT_FALSE(p.has_quat);
  // No battery (0), a battery of unknown level (0x80), no temperature (0), no RSSI (0).
  Bytes none = kInfo;
  none[2] = 0, none[3] = 0, none[4] = 0, none[15] = 0;
  const sh::Packet q = parse(none);
  EXPECT_TRUE(std::isnan(q.battery_fraction));
  EXPECT_TRUE(std::isnan(q.battery_v));
  EXPECT_TRUE(std::isnan(q.temperature_c));
  EXPECT_TRUE(std::isnan(q.rssi_dbm));
  none[2] = 0x80;
  EXPECT_TRUE(std::isnan(parse(none).battery_fraction));
  none[2] = 0xFF;  // charged: 127 % on the wire, 100 % here
  EXPECT_FLOAT_EQ(parse(none).battery_fraction, 1.0f);
}

TEST(SlimeVrHidTelemetry, TypesTwoToSevenInTheFirmwaresLayouts) {
  const sh::Packet c = parse(kCompact);
  expect_telemetry(c, 0.80f, 3.70f, 25.0f, -58.0f);
  ASSERT_TRUE(c.has_quat && c.has_accel);
  EXPECT_NEAR(c.quat_xyzw[3], 1.0, 1e-3);
  EXPECT_DOUBLE_EQ(c.accel_m_s2[2], 9.0);

  const sh::Packet s = parse(kStatusPacket);
  EXPECT_EQ(s.status, 1);
  ASSERT_TRUE(s.has_link_counts);
  EXPECT_EQ(s.packets_received, 200);
  EXPECT_EQ(s.packets_lost, 10);
  EXPECT_EQ(s.windows_hit, 50);
  EXPECT_EQ(s.windows_missed, 2);
  EXPECT_FLOAT_EQ(s.rssi_dbm, -55.0f);

  const sh::Packet r = parse(kRuntime);
  EXPECT_EQ(r.runtime_us, 3'600'000'000);
  EXPECT_FLOAT_EQ(r.rssi_dbm, -61.0f);
  Bytes unknown = kRuntime;
  for (int j = 2; j < 10; ++j)
    unknown[static_cast<std::size_t>(j)] = 0xFF;
  EXPECT_EQ(parse(unknown).runtime_us, -1);  // no estimate yet

  const sh::Packet b = parse(kButton);
  ASSERT_TRUE(b.has_button);
  EXPECT_EQ(b.button, 1);
  EXPECT_EQ(b.sleep_ms, 1000);
  EXPECT_FALSE(b.has_quat);
  EXPECT_FLOAT_EQ(b.rssi_dbm, -62.0f);

  const sh::Packet bq = parse(kButtonQuat);
  ASSERT_TRUE(bq.has_button && bq.has_quat && bq.has_accel);
  EXPECT_EQ(bq.button, 2);
  EXPECT_EQ(bq.sleep_ms, 10000);
  EXPECT_NEAR(bq.quat_xyzw[3], 1.0, 1e-3);
  EXPECT_DOUBLE_EQ(bq.accel_m_s2[2], 9.0);
  EXPECT_FLOAT_EQ(bq.rssi_dbm, -63.0f);

  // Types 1 and 4 have no room for the RSSI: byte 15 is data.
  Bytes full{};
  full[0] = sh::kQuatAccel;
  full[15] = 0x04;
  EXPECT_TRUE(std::isnan(parse(full).rssi_dbm));
  // A type nobody writes: not parsed.
  Bytes eight{};
  eight[0] = 8;
  sh::Packet p;
  EXPECT_FALSE(sh::parse_packet(std::span<const uint8_t, 16>(eight), p));
}

TEST(SlimeVrHidTelemetry, TheDecoderReportsEachTrackersTelemetryWhenItChanges) {
  auto dec = test::slimevr_dongle_decoder();
  test::CollectSink sink;
  dec->feed(report({&kRegister, &kInfo, &kCompact, &kStatusPacket}), 1'000'000'000, sink);
  dec->feed(report({&kRuntime, &kButton, &kButtonQuat}), 1'010'000'000, sink);
  const auto reports = sink.telemetry_snapshot();
  ASSERT_FALSE(reports.empty());
  for (const auto& [id, t] : reports)
    EXPECT_EQ(id, 4) << "only the registered tracker reports";
  const SensorTelemetry& t = reports.back().second;
  EXPECT_FLOAT_EQ(t.battery_fraction, 0.80f);
  EXPECT_FLOAT_EQ(t.battery_v, 3.70f);
  EXPECT_FLOAT_EQ(t.temperature_c, 25.0f);
  EXPECT_FLOAT_EQ(t.rssi_dbm, -63.0f);  // the newest packet's
  EXPECT_FLOAT_EQ(t.battery_runtime_s, 3600.0f);
  EXPECT_FLOAT_EQ(t.packet_loss, 10.0f / 210.0f);
  EXPECT_STREQ(t.board, "SlimeVR");
  EXPECT_STREQ(t.imu, "BMI270");
  EXPECT_STREQ(t.mcu, "MCU 12");  // a number the tables do not name
  EXPECT_STREQ(t.firmware, "0.6.2 (2025-03-14)");
  EXPECT_STREQ(t.address, "02:5E:00:00:00:A0");
  // Types 2 and 7 carry the orientation.
  EXPECT_EQ(sink.count(), 2u);
  // The same values again: nothing new to report.
  const std::size_t before = reports.size();
  dec->feed(report({&kButtonQuat}), 1'020'000'000, sink);
  EXPECT_EQ(sink.telemetry_snapshot().size(), before);
}

TEST(SlimeVrUdpTelemetry, BatterySignalAndTemperaturePacketsParse) {
  std::vector<uint8_t> d;
  slime_sim::battery(7, 3.7, 0.8, d);
  std::array<sv::Packet, 2> p;
  sv::Error err;
  ASSERT_EQ(sv::parse_datagram(d, p, err), 1u);
  EXPECT_FLOAT_EQ(p[0].battery_v, 3.7f);
  EXPECT_FLOAT_EQ(p[0].battery_level, 0.8f);
  d.clear();
  slime_sim::signal_strength(8, -60, d);
  EXPECT_EQ(d.size(), 14u);  // type, number, sensor id, i8
  ASSERT_EQ(sv::parse_datagram(d, p, err), 1u);
  EXPECT_EQ(p[0].sensor_id, 255);
  EXPECT_EQ(p[0].rssi_dbm, -60);
  d.clear();
  slime_sim::temperature(9, 1, 31.5, d);
  ASSERT_EQ(sv::parse_datagram(d, p, err), 1u);
  EXPECT_EQ(p[0].sensor_id, 1);
  EXPECT_FLOAT_EQ(p[0].temperature_c, 31.5f);
  // Truncated: refused.
  d.resize(d.size() - 2);
  EXPECT_EQ(sv::parse_datagram(d, p, err), 0u);
  EXPECT_EQ(err, sv::Error::kShort);
  // User actions as SlimeVR-Server numbers them (UDPPacket21UserAction).
  EXPECT_EQ(sv::kResetFull, 2);
  EXPECT_EQ(sv::kResetYaw, 3);
  EXPECT_EQ(sv::kResetMounting, 4);
  EXPECT_EQ(sv::kPauseTracking, 5);
}

TEST(SlimeVrUdpTelemetry, TheDecoderGivesEachSensorItsBoardsAndItsOwnFacts) {
  auto dec = test::slimevr_decoder("slimevr", "02:5E:00:00:00:01/0=3;02:5E:00:00:00:01/1=4");
  test::CollectSink sink;
  sv::Mac mac{};
  ASSERT_TRUE(sv::parse_mac("02:5E:00:00:00:01", mac));
  std::vector<uint8_t> d;
  int64_t t = 1'000'000'000;
  const auto feed = [&] {
    dec->feed(test::slimevr_record(d), t += 10'000'000, sink);
    d.clear();
  };
  slime_sim::handshake(mac, d);
  feed();
  slime_sim::battery(1, 3.7, 0.8, d);
  feed();
  slime_sim::signal_strength(2, -60, d);
  feed();
  slime_sim::temperature(3, 1, 31.5, d);
  feed();
  std::map<uint16_t, SensorTelemetry> last;
  for (const auto& [id, tel] : sink.telemetry_snapshot())
    last[id] = tel;
  ASSERT_EQ(last.size(), 2u);
  for (uint16_t id : {3, 4}) {
    const SensorTelemetry& s = last[id];
    EXPECT_STREQ(s.board, "SlimeVR") << id;
    EXPECT_STREQ(s.imu, "BMI270");
    EXPECT_STREQ(s.mcu, "ESP8266");
    EXPECT_STREQ(s.firmware, "0.6.0-sim");
    EXPECT_STREQ(s.address, "02:5E:00:00:00:01");
    EXPECT_FLOAT_EQ(s.battery_fraction, 0.8f);
    EXPECT_FLOAT_EQ(s.battery_v, 3.7f);
    EXPECT_FLOAT_EQ(s.rssi_dbm, -60.0f);  // the board's (sensor id 255)
  }
  EXPECT_TRUE(std::isnan(last[3].temperature_c));  // sensor 1's temperature is not sensor 0's
  EXPECT_FLOAT_EQ(last[4].temperature_c, 31.5f);
  // Unchanged values are not reported again.
  const std::size_t before = sink.telemetry_snapshot().size();
  slime_sim::battery(4, 3.7, 0.8, d);
  feed();
  EXPECT_EQ(sink.telemetry_snapshot().size(), before);
  slime_sim::battery(5, 3.6, 0.7, d);
  feed();
  EXPECT_EQ(sink.telemetry_snapshot().size(), before + 2);  // both sensors of the board
}

}  // namespace
}  // namespace mocap
