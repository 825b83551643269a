// The attitude filter's fixed constants: the stages' numbers that are not tuning parameters.
// All but kHeadingDevTau_s were FilterParams members; halved or doubled, most moved no BROAD mean
// by more than 0.03 deg, the estimators' model numbers up to 0.14, the upset verdict's only with
// clipped gyros (docs/filter.md, "Parameters"); the input bounds are limits, not tunings. The
// parameters (FilterParams, filter_params.hpp) are what real data or a sensor's make asks to set.
#pragma once

namespace mocap {

// Gyro bias Kalman filter.
inline constexpr double kBiasSigmaInit_deg_s = 0.5;      ///< deg/s, initial bias uncertainty
inline constexpr double kBiasVerticalForgetting = 1e-4;  ///< -, vertical pseudo-measurement weight

// Gyro gain Kalman filter.
inline constexpr double kGyrGainForgettingTime_s = 100;  ///< s, uncertainty grows by 0.001
inline constexpr double kGyrGainClip = 0.05;             ///< -, largest estimate per entry

// Rest detection.
inline constexpr double kRestFilterTau_s = 0.5;  ///< s, low-pass of the rest deviations

// Magnetic disturbance.
/// s, smoothing of the heading innovation for the disturbance test (norm and dip:
/// kMagCurrentTau_s): the field's heading is noisier than its norm and dip.
inline constexpr double kHeadingDevTau_s = 0.5;
inline constexpr double kMagCurrentTau_s = 0.05;         ///< s, smoothing of the field's norm, dip
inline constexpr double kMagNewFirstTime_s = 5.0;        ///< s, the first field accepted after this
inline constexpr double kMagNewMinGyr_deg_s = 20.0;      ///< deg/s, a candidate ages only this fast
inline constexpr double kMagMinUndisturbedTime_s = 0.5;  ///< s, undisturbed this long to be used
inline constexpr double kMagMaxRejectionTime_s = 60.0;   ///< s, longest full rejection
inline constexpr double kMagRejectionFactor = 2.0;       ///< -, gain divisor after that

// Hard-iron estimator; noises, gates and offsets as fractions of the field norm F.
inline constexpr double kHardIronSigma0 = 1.0;       ///< x F, prior one-sigma of the offset
inline constexpr double kHardIronFieldRw_deg = 0.3;  ///< deg/sqrt(s), field drift, 6D frame
inline constexpr double kHardIronNoise = 0.03;       ///< x F, measurement one-sigma
inline constexpr double kHardIronMinOffset = 0.02;   ///< x F, smallest offset applied
inline constexpr double kHardIronMinSigmas = 3.0;    ///< sigmas, smallest significance applied
inline constexpr double kHardIronNisTau_s = 2.0;     ///< s, averaging of the innovations' NIS
inline constexpr double kHardIronNisMax = 9.0;       ///< -, above: model broken, restart
inline constexpr double kHardIronStep_s = 0.1;       ///< s, estimator period (decimated)
/// The offset is applied only while it explains a disturbance: the field's norm/dip deviation
/// from the reference (squared, relative to the thresholds, as the soft trust) with and
/// without it, the difference low-passed over kHardIronSelectTau_s; the offset's weight ramps
/// from 0 to 1 as that difference goes from 0 to kHardIronSelectMargin.
inline constexpr double kHardIronSelectTau_s = 1.0;   ///< s
inline constexpr double kHardIronSelectMargin = 0.2;  ///< -

// Magnetometer latency estimate.
inline constexpr double kMagLatencyHpTau_s = 0.5;         ///< s, high-pass of the field, its rate
inline constexpr double kMagLatencyMinRate_deg_s = 30.0;  ///< deg/s, below: the estimate shrinks
inline constexpr double kMagLatencyMax_s = 0.05;          ///< s, largest latency compensated

// Input bounds: what is integrated or rejected (counted in FilterCounters).
inline constexpr double kMaxGap_s = 0.25;      ///< s, longer gaps are not integrated
inline constexpr double kMaxGyr_rad_s = 70.0;  ///< rad/s, rejected above (about 4000 deg/s)
inline constexpr double kMaxAcc_m_s2 = 500.0;  ///< m/s^2, rejected above (about 50 g)
inline constexpr double kMaxMag_uT = 10000.0;  ///< uT, rejected above

// Upset recovery: for kUpsetWindow_s after a clipped sample a fresh orientation from acc (and
// the field) low-passed over kUpsetTau_s is compared with the filter's. Verdicts, each held
// for kUpsetHold_s while the fresh orientation turns less than kUpsetSteady_deg there (a
// swing's specific force turns; a lost rotation is fixed) and the fast acc's norm is within
// kUpsetNormTol of g: the inclination lost (off by over kUpsetAngle_deg): set to the fresh
// one; with the inclination confirmed (within kUpsetConfirm_deg) and the field passing its
// tests, the heading lost: set to the field's; both confirmed: the check ends.
inline constexpr double kUpsetTau_s = 0.3;        ///< s
inline constexpr double kUpsetWindow_s = 10.0;    ///< s
inline constexpr double kUpsetAngle_deg = 30.0;   ///< deg
inline constexpr double kUpsetConfirm_deg = 5.0;  ///< deg
inline constexpr double kUpsetSteady_deg = 5.0;   ///< deg
inline constexpr double kUpsetHold_s = 0.2;       ///< s
inline constexpr double kUpsetNormTol = 0.1;      ///< -, relative to g

}  // namespace mocap
