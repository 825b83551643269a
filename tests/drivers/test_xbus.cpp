// Xbus: the quaternion's coordinate bits (data id 0x2010 ENU, 0x2014 NED, 0x2018 NWU) decide its
// earth frame; every sample leaves the driver sensor-to-ENU.
#include <gtest/gtest.h>

#include <cmath>

#include "collect_sink.hpp"
#include "mocap/drivers/xbus.hpp"

using namespace mocap;

namespace {
// One MTData2 message: packet counter, sample time, the quaternion under data id `quat_id`.
std::vector<uint8_t> frame(uint16_t counter, uint32_t t, uint16_t quat_id,
                           const Eigen::Quaterniond& q) {
  std::vector<uint8_t> payload;
  auto put = [&](uint32_t v, int bytes) {
    for (int k = bytes - 1; k >= 0; --k)
      payload.push_back(static_cast<uint8_t>(v >> (8 * k)));
  };
  put(xbus::kPacketCounter, 2), put(2, 1), put(counter, 2);
  put(xbus::kSampleTimeFine, 2), put(4, 1), put(t, 4);
  const double v[4] = {q.w(), q.x(), q.y(), q.z()};
  xbus::put_floats(quat_id, v, payload);
  std::vector<uint8_t> out;
  xbus::encode(xbus::kMtData2, payload, out);
  return out;
}

ImuSample decode_one(uint16_t quat_id, const Eigen::Quaterniond& q) {
  DeviceSpec spec{.name = "x", .protocol = "xbus"};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  dec->feed(frame(1, 1000, quat_id, q), 0, sink);
  EXPECT_EQ(sink.samples.size(), 1u);
  return sink.samples.empty() ? ImuSample{} : sink.samples[0];
}
}  // namespace

TEST(Xbus, NedQuaternionBecomesEnu) {
  // A sensor lying with x to the north and z down: identity in NED.
  const ImuSample s = decode_one(0x2014, Eigen::Quaterniond::Identity());
  ASSERT_TRUE(s.has(kFieldQuat));
  const Eigen::Matrix3d r = s.q_device_sensor.toRotationMatrix();        // sensor -> ENU
  EXPECT_TRUE(r.col(0).isApprox(Eigen::Vector3d(0, 1, 0), 1e-6)) << r;   // x north
  EXPECT_TRUE(r.col(1).isApprox(Eigen::Vector3d(1, 0, 0), 1e-6)) << r;   // y east
  EXPECT_TRUE(r.col(2).isApprox(Eigen::Vector3d(0, 0, -1), 1e-6)) << r;  // z down
}

TEST(Xbus, SameAttitudeInEnuNedAndNwuAgrees) {
  // One attitude (sensor -> ENU), sent in each of the three frames as an MTi would send it.
  const Eigen::Quaterniond q_enu =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  Eigen::Matrix3d ned_from_enu, nwu_from_enu;
  ned_from_enu << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  nwu_from_enu << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  const Eigen::Quaterniond q_ned(ned_from_enu * q_enu.toRotationMatrix());
  const Eigen::Quaterniond q_nwu(nwu_from_enu * q_enu.toRotationMatrix());
  for (auto [id, q] : {std::pair{uint16_t{0x2010}, q_enu}, std::pair{uint16_t{0x2014}, q_ned},
                       std::pair{uint16_t{0x2018}, q_nwu}}) {
    SCOPED_TRACE(id);
    const ImuSample s = decode_one(id, q);
    ASSERT_TRUE(s.has(kFieldQuat));
    EXPECT_LT(s.q_device_sensor.angularDistance(q_enu), 1e-5);
  }
}

TEST(Xbus, ReservedCoordinateBitsDropTheQuaternion) {
  DeviceSpec spec{.name = "x", .protocol = "xbus"};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  dec->feed(frame(1, 1000, 0x201C, Eigen::Quaterniond::Identity()), 0, sink);
  for (const auto& s : sink.samples)
    EXPECT_FALSE(s.has(kFieldQuat));
  EXPECT_EQ(dec->stats().resyncs, 1u);
}
