// End to end for the USB HID controllers: the real StreamDevice (set-up steps: feature-report
// read, Joy-Con handshake and subcommands; reader thread; decoder) runs on a simulated HID
// transport whose reports come from the protocol encoder, and the decoded samples are checked
// against the simulated truth. Report-level tests cover drops and timestamp rollover.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "collect_sink.hpp"
#include "mocap/core/units.hpp"
#include "mocap/devsim/sim_transport.hpp"
#include "mocap/drivers/joycon.hpp"
#include "mocap/drivers/playstation.hpp"

using namespace mocap;

namespace {

struct Case {
  const char* protocol;
  double rate_hz;
  double gyr_tol_rad_s, acc_tol_m_s2;  // one LSB of the device
};

void run_case(const Case& c, std::map<std::string, std::string> enc_opts = {},
              std::map<std::string, std::string> dev_opts = {}) {
  auto motion = make_motion("rotate");
  const Motion* truth = motion.get();
  DeviceSpec spec{
      .name = c.protocol, .protocol = c.protocol, .port = "hid:0:0", .options = dev_opts};
  auto dev = make_device_with_transport(
      spec, Logger(test::g_log_sink, "test", LogLevel::warn),
      [&](std::string&) -> std::unique_ptr<ByteTransport> {
        return std::make_unique<SimReportTransport>(
            make_encoder(c.protocol, {.rate_hz = c.rate_hz, .options = enc_opts}),
            make_motion("rotate"));
      });
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 300; })) << c.protocol;
  dev->stop();
  const auto got = sink.snapshot();
  double eg = 0, ea = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto& s = got[i];
    ASSERT_TRUE(s.has(kFieldGyr) && s.has(kFieldAcc));
    if (i > 0) {
      EXPECT_GT(s.t_device_ns, got[i - 1].t_device_ns) << c.protocol << " sample " << i;
    }
    const ImuSample t = truth->at(s.t_device_ns);
    eg = std::max(eg, (s.gyr_rad_s - t.gyr_rad_s).cwiseAbs().maxCoeff());
    ea = std::max(ea, (s.acc_m_s2 - t.acc_m_s2).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(eg, c.gyr_tol_rad_s) << c.protocol;
  EXPECT_LT(ea, c.acc_tol_m_s2) << c.protocol;
  EXPECT_EQ(dev->stats().decoder.dropped_samples, 0u) << c.protocol;
  std::printf(
      "%s/hid: %zu samples over %.2f s of device time, max err gyr %.2e rad/s acc %.2e m/s2\n",
      c.protocol, got.size(), (got.back().t_device_ns - got.front().t_device_ns) * 1e-9, eg, ea);
}

}  // namespace

TEST(E2eHid, Ds4WithCalibrationAndTimestampRollover) {
  // 250 Hz, 16/3 us ticks: the uint16 timestamp wraps every 0.35 s, several times here.
  run_case({"ds4", 250, 0.0012, 0.0013});
}

TEST(E2eHid, DualSense) {
  run_case({"dualsense", 250, 0.0012, 0.0013});
}

TEST(E2eHid, JoyconHandshakeCalibrationAndThreeSamplesPerReport) {
  // The simulated controller sends nothing until the driver's USB handshake, report-mode and
  // IMU-enable subcommands; its factory calibration is only known through the SPI read.
  run_case({"joycon", 200, 0.0013, 0.0025}, {{"wait_for_host", "1"}});
}

TEST(E2eHid, JoyconUserCalibrationWinsOverFactory) {
  // The controller's IMU reads through a user calibration (magic B2 A1 at SPI 0x8026) that
  // differs from its factory one: decoding with the factory one would miss the tolerance.
  run_case({"joycon", 200, 0.0013, 0.0025}, {{"wait_for_host", "1"}, {"user_cal", "1"}});
}

TEST(E2eHid, RightJoyconAxesMatchTheLeft) {
  run_case({"joycon", 200, 0.0013, 0.0025}, {{"side", "right"}}, {{"side", "right"}});
}

TEST(PlaystationReports, DropsCountedFromTimestamps) {
  auto enc = make_encoder("ds4", {.rate_hz = 250});
  auto motion = make_motion("rotate");
  auto dec = make_decoder({.name = "d", .protocol = "ds4"});
  test::CollectSink sink;
  std::vector<uint8_t> cal;
  ASSERT_TRUE(enc->feature_report(playstation::kDs4CalibUsb, cal));
  dec->feed(cal, 0, sink);
  int withheld = 0;
  for (int i = 0; i < 500; ++i) {
    std::vector<uint8_t> r;
    enc->encode(motion->at(int64_t{i} * 4'000'000), r);
    if (i % 17 == 5) {
      ++withheld;
      continue;
    }
    dec->feed(r, 1'000'000'000 + int64_t{i} * 4'000'000, sink);
  }
  EXPECT_EQ(dec->stats().dropped_samples, static_cast<uint64_t>(withheld));
  EXPECT_EQ(sink.samples.size(), 500u - withheld);
  // A truncated and a foreign report are rejected, not decoded.
  std::vector<uint8_t> r;
  enc->encode(motion->at(0), r);
  dec->feed(std::span(r).first(20), 0, sink);
  r[0] = 0x11;
  dec->feed(r, 0, sink);
  EXPECT_EQ(sink.samples.size(), 500u - withheld);
  EXPECT_EQ(dec->stats().resyncs, 2u);
}

TEST(PlaystationReports, CalibrationLayoutsAndFallback) {
  using namespace playstation;
  // BT layout (0x05 for DS4) interleaves plus/minus differently from USB (0x02).
  std::vector<uint8_t> bt(kCalib41Size, 0);
  bt[0] = kCalibBt;
  auto put = [&](int off, int16_t v) {
    bt[off] = v & 0xFF, bt[off + 1] = (uint16_t(v) >> 8) & 0xFF;
  };
  put(7, 100), put(9, 200), put(11, 300), put(13, -100), put(15, -200), put(17, -300);
  Calibration c;
  ASSERT_TRUE(parse_calibration(Model::kDs4, bt, c));
  EXPECT_EQ(c.gyr_plus[1], 200);
  EXPECT_EQ(c.gyr_minus[0], -100);
  // Zero spans (clone controllers) fall back to the fixed scale instead of dividing by zero.
  const Scale s = scale_from(Calibration{});
  EXPECT_DOUBLE_EQ(s.gyr_dps_per_lsb[0], 2048.0 / 32767);
  EXPECT_DOUBLE_EQ(s.acc_g_per_lsb[2], 4.0 / 32767);
}

TEST(JoyconReports, CalibrationFormulasAndZeroDivisor) {
  joycon::Calibration c;
  EXPECT_NEAR(joycon::acc_g(c, 0, 4096), 1.0, 1e-12);
  EXPECT_NEAR(joycon::gyr_dps(c, 1, 14247), 1000.0, 1e-9);
  c.gyr_sens[2] = c.gyr_offset[2] = 7;  // divisor 0 -> 1, no crash
  EXPECT_TRUE(std::isfinite(joycon::gyr_dps(c, 2, 100)));
}

namespace {
// A 0x21 reply to an SPI read of `len` bytes at `addr`, carrying `bytes`.
std::vector<uint8_t> spi_reply(uint32_t addr, uint8_t len, std::span<const uint8_t> bytes) {
  std::vector<uint8_t> r(joycon::kReportSize, 0);
  r[0] = joycon::kInputReply, r[13] = 0x90, r[14] = joycon::kSubSpiRead;
  for (int k = 0; k < 4; ++k)
    r[15 + k] = static_cast<uint8_t>(addr >> (8 * k));
  r[19] = len;
  std::copy(bytes.begin(), bytes.end(), r.begin() + 20);
  return r;
}
// A 0x30 report whose three samples all read `acc` and `gyr` (raw).
std::vector<uint8_t> full_report(uint8_t timer, int16_t acc, int16_t gyr) {
  std::vector<uint8_t> r(joycon::kReportSize, 0);
  r[0] = joycon::kInputFull, r[1] = timer;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      r[13 + 12 * i + 2 * k] = static_cast<uint8_t>(acc), r[14 + 12 * i + 2 * k] = acc >> 8;
      r[19 + 12 * i + 2 * k] = static_cast<uint8_t>(gyr), r[20 + 12 * i + 2 * k] = gyr >> 8;
    }
  return r;
}
// Decodes one report after the given SPI replies; returns the first sample's gyro x in dps.
double gyro_x_dps_after(const std::vector<std::vector<uint8_t>>& replies) {
  auto dec = make_decoder({.name = "j", .protocol = "joycon"});
  test::CollectSink sink;
  for (const auto& r : replies)
    dec->feed(r, 0, sink);
  dec->feed(full_report(1, 4096, 1000), 0, sink);
  EXPECT_EQ(sink.samples.size(), 3u);
  return sink.samples.empty() ? 0 : sink.samples[0].gyr_rad_s.x() * kDegPerRad;
}
}  // namespace

TEST(JoyconReports, UserCalibrationWhenMagicPresentElseFactory) {
  joycon::Calibration factory, user;
  factory.gyr_offset = {10, 10, 10};
  user.gyr_offset = {-200, -200, -200};
  user.gyr_sens = {13000, 13000, 13000};
  std::array<uint8_t, joycon::kImuCalibSize> fb{}, ub_cal{};
  joycon::encode_calibration(factory, fb);
  joycon::encode_calibration(user, ub_cal);
  std::vector<uint8_t> with_magic(joycon::kImuUserReadSize);
  with_magic[0] = joycon::kUserCalibMagic0, with_magic[1] = joycon::kUserCalibMagic1;
  std::copy(ub_cal.begin(), ub_cal.end(), with_magic.begin() + 2);
  std::vector<uint8_t> erased(joycon::kImuUserReadSize, 0xFF);
  const auto user_reply = spi_reply(joycon::kSpiImuUserCalib, joycon::kImuUserReadSize, with_magic);
  const auto erased_reply = spi_reply(joycon::kSpiImuUserCalib, joycon::kImuUserReadSize, erased);
  const auto factory_reply = spi_reply(joycon::kSpiImuFactoryCalib, joycon::kImuCalibSize, fb);
  const double want_user = joycon::gyr_dps(user, 0, 1000);
  const double want_factory = joycon::gyr_dps(factory, 0, 1000);
  ASSERT_GT(std::fabs(want_user - want_factory), 1.0);
  // User calibration present: used, whichever reply comes first.
  EXPECT_NEAR(gyro_x_dps_after({user_reply, factory_reply}), want_user, 1e-9);
  EXPECT_NEAR(gyro_x_dps_after({factory_reply, user_reply}), want_user, 1e-9);
  // No magic (erased flash): the factory calibration.
  EXPECT_NEAR(gyro_x_dps_after({erased_reply, factory_reply}), want_factory, 1e-9);
  EXPECT_NEAR(gyro_x_dps_after({factory_reply}), want_factory, 1e-9);
}

TEST(E2eHid, ControllersOverUdpDatagrams) {
  // A controller bridged over UDP (one report per datagram, calibration repeated unsolicited):
  // the same decoder through the real UDP transport.
  for (const char* proto : {"ds4", "joycon"}) {
    const std::string addr = "127.0.0.1:" + std::to_string(test::free_loopback_port(SOCK_DGRAM));
    DeviceSpec spec{.name = proto,
                    .protocol = proto,
                    .port = "udp:" + addr,
                    .options = {{"usb_handshake", "0"}}};
    auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::error));
    test::CollectSink sink;
    dev->start(sink);
    // The socket must be bound before the simulator's first datagram (its calibration).
    ASSERT_TRUE(sink.wait_for([&] { return !sink.events_snapshot().empty(); }));
    SimulatedDevice sim({.protocol = proto, .rate_hz = 200, .motion = "rotate", .udp = addr});
    sim.start();
    ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 150; })) << proto;
    sim.stop();
    dev->stop();
    double eg = 0;
    int64_t worst_t = 0;
    std::size_t worst_i = 0, i = 0;
    const auto got = sink.snapshot();
    for (const auto& s : got) {
      const double e =
          (s.gyr_rad_s - sim.motion().at(s.t_device_ns).gyr_rad_s).cwiseAbs().maxCoeff();
      if (e > eg) eg = e, worst_t = s.t_device_ns, worst_i = i;
      ++i;
    }
    if (eg >= 0.0013)
      std::printf("%s: worst sample %zu of %zu at device t %.6f s\n", proto, worst_i, got.size(),
                  worst_t * 1e-9);
    EXPECT_LT(eg, 0.0013) << proto;
  }
}
