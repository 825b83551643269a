// Madgwick and Mahony baselines on synthetic truth: they start from acc+mag, converge at rest
// and track a rotation (loose bounds: these are the reference methods, not ours).
#include <gtest/gtest.h>

#include "mocap/eval/madgwick.hpp"
#include "mocap/eval/mahony.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

template <class F>
double max_err_after(F& f, const SynthStream& s, double t0) {
  double m = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    f.update(s.samples[i]);
    if (s.samples[i].t_host_ns * 1e-9 >= t0)
      m = std::max(m, angle_deg(f.q_earth_sensor(), s.truth[i]));
  }
  return m;
}

SynthStream rotating() {
  SynthConfig c;
  c.duration_s = 30;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()));
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return t < 5 ? Eigen::Vector3d::Zero().eval()
                 : Eigen::Vector3d(0.5 * std::sin(0.7 * t), 0.3, 0.6 * std::cos(0.4 * t));
  };
  return make_stream(c);
}

TEST(Baselines, MadgwickInitialisesAndTracks) {
  const auto s = rotating();
  MadgwickFilter f;
  f.update(s.samples[0]);
  EXPECT_LT(angle_deg(f.q_earth_sensor(), s.truth[0]), 1.0);  // ENU start from acc+mag
  EXPECT_LT(max_err_after(f, s, 0.0), 3.0);
}

TEST(Baselines, MahonyInitialisesAndTracks) {
  const auto s = rotating();
  MahonyFilter f;
  f.update(s.samples[0]);
  EXPECT_LT(angle_deg(f.q_earth_sensor(), s.truth[0]), 1.0);
  EXPECT_LT(max_err_after(f, s, 0.0), 3.0);
}

TEST(Baselines, MadgwickCorrectsAWrongStart) {
  auto s = rotating();
  MadgwickFilter f;
  // Start from a sample whose acc is tilted by 30 deg: the filter must pull back.
  ImuSample first = s.samples[0];
  first.acc_m_s2 = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()) * first.acc_m_s2;
  f.update(first);
  EXPECT_GT(angle_deg(f.q_earth_sensor(), s.truth[0]), 20.0);
  for (size_t i = 1; i < 500; ++i)
    f.update(s.samples[i]);  // 5 s at rest
  EXPECT_LT(angle_deg(f.q_earth_sensor(), s.truth[499]), 2.0);
}

}  // namespace
}  // namespace mocap::test
