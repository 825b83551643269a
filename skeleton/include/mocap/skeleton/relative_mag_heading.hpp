// Relative magnetometer heading smoothing: joint rotations from the gyros in the short term, from
// the magnetometers in the long term.
//
// Why: each sensor's filter turns its heading by its own magnetometer (AttitudeFilter: q_earth =
// Rz(delta) q_gyro_acc, delta following the field with a ~9 s time constant). A hard-iron
// residual of ~1 uT per axis makes that field heading wrong by a few degrees, by an amount that
// changes as the sensor changes orientation (raising an arm, squatting), differently on every
// sensor; the filters follow it and every joint between two sensors shows the difference. The
// gyros measure the same short-term motion far better (measured: with the magnetometers frozen
// after the calibration the 3-DOF joint error of a squat falls from 3.1 to 1.1 deg). So each
// sensor's magnetometer correction relative to the reference sensor's (the root-most tracked
// segment, the pelvis) is low-passed with tau_s: the difference delta_i - delta_ref is replaced
// by its low-passed value, i.e. q_i <- Rz(lp_i - (delta_i - delta_ref)) q_i. The reference keeps
// its own heading (the body's heading and walking direction stay as fast as the filter's), and
// any joint's relative heading is LP(delta_c - delta_ref) - LP(delta_p - delta_ref) =
// LP(delta_c - delta_p): the two filters' relative correction, smoothed.
//
// Turns are the exception: turning about the vertical, every gyro's scale error (~0.5 %) turns
// its heading by a different amount (a 180 deg turn: 1-3 deg between two sensors), which only
// the magnetometers see, and the filters absorb it over their own time constant after the turn.
// So each segment's rotation about the earth vertical is summed into a turn budget that decays
// with turn_memory_s (the filters' heading time constant); while it holds turn_deg or more, the
// relative correction follows the filters' with turn_tau_s (a fraction of that below). Sensors
// whose gyro scale is calibrated (filter/gyro_scale.hpp) do not turn apart: the turn rule is
// skipped for a segment when both its sensor and the reference's are (it would only let the
// magnetometers' errors back in).
//
// Pure, deterministic, allocation-free; one instance per skeleton, reset with the calibration
// (which was taken from the sensors' own headings).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/rig.hpp"

namespace mocap {

struct RelativeMagHeadingOptions {
  bool enabled = false;
  double tau_s = 20.0;         ///< time constant of the relative correction
  double turn_deg = 90.0;      ///< turning (about the vertical) that switches to turn_tau_s
  double turn_memory_s = 9.0;  ///< decay of the turn budget
  double turn_tau_s = 2.0;     ///< time constant after turning
  /// Segments whose sensor's gyro scale is calibrated (no turn rule between two of them).
  std::array<bool, kSegmentCount> gyro_scale_calibrated{};
};

class RelativeMagHeading {
 public:
  RelativeMagHeading(RigMapping rig, RelativeMagHeadingOptions options);

  /// Forgets the smoothing: the next sample of each sensor starts from its own heading.
  void reset();
  /// One sensor orientation and its filter's magnetometer heading correction
  /// (AttitudeFilter::mag_heading_rad(); NaN while it has none or it has not converged);
  /// returns the orientation with the relative correction smoothed. A NaN passes the sample
  /// unchanged and restarts the segment's smoothing (every segment's for the reference).
  /// Pass-through when disabled, for the reference segment, and while the reference has none.
  Eigen::Quaterniond apply(int segment, const Eigen::Quaterniond& q_earth_sensor, int64_t t_ns,
                           double mag_heading_rad);
  /// The heading turned onto each segment (rad): smoothed minus actual relative correction.
  double correction_rad(int segment) const { return correction_rad_[segment]; }
  int reference() const { return ref_; }
  const RelativeMagHeadingOptions& options() const { return opt_; }

 private:
  RelativeMagHeadingOptions opt_;
  int ref_ = -1;  ///< reference segment (-1: none tracked)
  double ref_rad_ = 0;
  bool have_ref_ = false;
  std::array<bool, kSegmentCount> have_{};
  std::array<double, kSegmentCount> lp_rad_{};          ///< low-passed relative correction
  std::array<double, kSegmentCount> turn_rad_{};        ///< turn budget
  std::array<double, kSegmentCount> correction_rad_{};  ///< last applied
  std::array<int64_t, kSegmentCount> t_ns_{};
  std::array<Eigen::Quaterniond, kSegmentCount> q_prev_;
};

}  // namespace mocap
