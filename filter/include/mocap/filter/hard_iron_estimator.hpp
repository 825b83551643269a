// Online hard-iron estimate: a sensor-fixed field offset b (a magnet or magnetised part on the
// housing) from the gyro-predicted rotation of the field. The magnetometer reads
// m = R^T c + b, c = the field in the (6D) earth frame, R = sensor -> earth from gyro + acc:
// the earth part turns with the sensor, b does not, so rotation separates them without a
// sphere fit. A 6-state Kalman filter (c, b) with random-walk forgetting; its covariance
// says, per direction, how well b is known, and only well-known directions are used. Plain
// data (part of FilterState's HardIronState).
#pragma once

#include <Eigen/Core>

namespace mocap {

/// Noise and gates, all relative to the field norm F and per second (rate-independent).
struct HardIronCoeffs {
  double q_field_rel2_s = 0;   ///< variance growth of c per second, in F^2
  double q_offset_rel2_s = 0;  ///< variance growth of b per second, in F^2
  double p0_offset_rel2 = 0;   ///< prior variance of b (and largest), in F^2
  double r_rel2 = 0;           ///< measurement variance, in F^2
  double gate_rel2 = 0;        ///< b directions with variance below this are used, in F^2
  double min_offset_rel = 0;   ///< offsets smaller than this (x F) are not applied
  double min_sigmas = 0;       ///< nor offsets less significant than this (sigmas)
  double k_nis = 0;            ///< first-order gain of the innovation-consistency average
  double nis_max = 0;          ///< above this the model (constant c, b) is broken: restart
};

struct HardIronEstimator {
  Eigen::Vector3d c_uT = Eigen::Vector3d::Zero();  ///< field in the 6D earth frame
  Eigen::Vector3d b_uT = Eigen::Vector3d::Zero();  ///< offset estimate, sensor frame
  Eigen::Matrix<double, 6, 6> p = Eigen::Matrix<double, 6, 6>::Zero();  ///< in uT^2
  double f_uT = 0;                                    ///< field norm the noises refer to
  double nis = 1;                                     ///< averaged normalised innovation
  Eigen::Vector3d used_uT = Eigen::Vector3d::Zero();  ///< gated offset, what the filter subtracts
  double used_sigma_uT = 0;    ///< largest one-sigma of used_uT over its directions (0 = unused)
  double offset_sigma_uT = 0;  ///< largest one-sigma of b over all directions (each step)
  bool init = false;
  int restarts = 0;

  /// m_uT: field in the sensor frame (latency-compensated); r_es: sensor -> 6D earth; dt_s:
  /// time since the last step; f_ref_uT: the reference (earth) field norm the relative noises
  /// refer to, 0 while unknown (then the first field's norm).
  void step(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es, double dt_s, double f_ref_uT,
            const HardIronCoeffs& k);

 private:
  /// True when it ended with gate() (which then set offset_sigma_uT).
  bool update(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es, double dt_s,
              const HardIronCoeffs& k);
  void restart(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es, const HardIronCoeffs& k);
  void gate(const HardIronCoeffs& k);  ///< also sets offset_sigma_uT
};

}  // namespace mocap
