// Built-in procedural motions: each clip is a C2-smooth function of time giving joint angles that
// start and end in the N-pose, so clips string together into sequences without jumps.
// Angle conventions (segment frames x forward, y left, z up): flexion of hip and shoulder lifts the
// limb forward = rotation about y by -angle; knee flexion = +angle about y; elbow flexion = -angle
// about y; left-arm abduction = +angle about x, right-arm abduction = -angle about x.
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <stdexcept>

#include "calibration_procedure.hpp"
#include "mocap/core/units.hpp"
#include "mocap/sim/motion.hpp"
#include "smoothstep.hpp"

namespace mocap::sim {
namespace {

using Eigen::Quaterniond;
using Eigen::Vector3d;

Quaterniond rx(double deg) {
  return Quaterniond(Eigen::AngleAxisd(deg * kRadPerDeg, Vector3d::UnitX()));
}
Quaterniond ry(double deg) {
  return Quaterniond(Eigen::AngleAxisd(deg * kRadPerDeg, Vector3d::UnitY()));
}
Quaterniond rz(double deg) {
  return Quaterniond(Eigen::AngleAxisd(deg * kRadPerDeg, Vector3d::UnitZ()));
}

/// C2 bump on [0,1]: 0 at the ends (with zero first and second derivative... first only is
/// guaranteed zero for 64u^3(1-u)^3, second is zero too), 1 at u = 0.5.
double bump(double u) {
  if (u <= 0 || u >= 1) return 0;
  const double v = u * (1 - u);
  return 64 * v * v * v;
}
/// Amplitude envelope: ramps 0 -> 1 over `ramp` seconds at the start and back to 0 at the end.
double envelope(double t, double d, double ramp) {
  return smoothstep5(t / ramp) * smoothstep5((d - t) / ramp);
}
double frac(double x) {
  return x - std::floor(x);
}

void set(BodyPose& p, Segment s, const Quaterniond& q) {
  p.q_parent_segment[index(s)] = q;
}

/// One leg: hip flexion, knee flexion; the ankle sets the foot's earth pitch to
/// `pelvis_pitch_deg` minus that value, i.e. level when the pelvis pitch is passed, toe down by t
/// when -t is passed with a level pelvis.
void leg(BodyPose& p, bool left, double hip_deg, double knee_deg, double pelvis_pitch_deg) {
  const Segment thigh = left ? Segment::thigh_l : Segment::thigh_r;
  const Segment shank = left ? Segment::shank_l : Segment::shank_r;
  const Segment foot = left ? Segment::foot_l : Segment::foot_r;
  set(p, thigh, ry(-hip_deg));
  set(p, shank, ry(knee_deg));
  set(p, foot, ry(hip_deg - knee_deg - pelvis_pitch_deg));
}

struct Clip {
  enum Kind { kStand, kWalk, kTurn, kSquat, kArmRaise, kReach, kCalibrationMoves } kind;
  double duration_s;
  double yaw_change_deg = 0;  // heading change over the clip (turn)
};

void stand(double, double, BodyPose&) {}

void walk(double t, double d, BodyPose& p) {
  const double cycle_s = 1.1;
  const double swing_hip_deg = 22, swing_toe_down_deg = 30;
  const double a = envelope(t, d, 1.0);
  const double phase_l = t / cycle_s, phase_r = phase_l + 0.5;
  const double c_l = std::cos(2 * std::numbers::pi * phase_l);
  // Own phase 0: heel strike with the hip flexed 20 deg; stance while the hip extends to -20
  // (phase 0.5); the heel rises from 0.3 (the foot rolls onto the toe, up to 30 deg at toe-off)
  // and the knee flexes up to 60 deg in swing. In swing the hip flexes early (to ~25 deg by
  // late swing, then back to 20 at heel strike) and the foot points toe-down after toe-off (up
  // to ~45 deg while the knee flexes), levelling out by late swing for the flat landing: the
  // ankle dorsiflexes at most ~12 deg (the level swing foot reached ~60, beyond the 20 deg
  // limit) and the toe clears the floor by ~3 cm when the feet pass.
  auto leg_at = [&](bool left, double phase) {
    const double u = frac(phase);
    const double hip =
        a * (20 * std::cos(2 * std::numbers::pi * phase) + swing_hip_deg * bump((u - 0.55) / 0.45));
    const double knee = a * 60 * bump((u - 0.45) / 0.55);
    const double toe_down =
        a * (30 * bump((u - 0.3) / 0.5) + swing_toe_down_deg * bump((u - 0.5) / 0.4));
    leg(p, left, hip, knee, -toe_down);
  };
  leg_at(true, phase_l);
  leg_at(false, phase_r);
  p.q_earth_pelvis = rz(-4 * a * c_l);
  set(p, Segment::torso, rz(4 * a * c_l) * ry(3 * a));
  set(p, Segment::neck, ry(-3 * a));
  const double s_l = std::sin(2 * std::numbers::pi * phase_l);
  set(p, Segment::upper_arm_l, ry(18 * a * c_l) * rx(5 * a));
  set(p, Segment::upper_arm_r, ry(-18 * a * c_l) * rx(-5 * a));
  set(p, Segment::forearm_l, ry(-a * (20 + 8 * s_l)));
  set(p, Segment::forearm_r, ry(-a * (20 - 8 * s_l)));
}

void turn(double t, double d, double yaw_deg, BodyPose& p) {
  const double step_cycle_s = 0.9;  // left step then right step
  const double a = envelope(t, d, 0.4);
  const double u = frac(t / step_cycle_s);
  const double lift_l = a * bump(u / 0.5), lift_r = a * bump((u - 0.5) / 0.5);
  leg(p, true, 25 * lift_l, 45 * lift_l, 0);
  leg(p, false, 25 * lift_r, 45 * lift_r, 0);
  p.q_earth_pelvis = rz(yaw_deg * smoothstep5((t - 0.3) / (d - 0.6)));
  set(p, Segment::forearm_l, ry(-15 * a));
  set(p, Segment::forearm_r, ry(-15 * a));
}

void squat(double t, double d, BodyPose& p) {
  const double half = d / 2;
  const double u = bump(std::fmod(t, half) / half);
  p.q_earth_pelvis = ry(20 * u);
  leg(p, true, 100 * u, 105 * u, 20 * u);
  leg(p, false, 100 * u, 105 * u, 20 * u);
  set(p, Segment::torso, ry(15 * u));
  set(p, Segment::neck, ry(-20 * u));
  set(p, Segment::head, ry(-15 * u));
  set(p, Segment::upper_arm_l, ry(-80 * u));
  set(p, Segment::upper_arm_r, ry(-80 * u));
  set(p, Segment::forearm_l, ry(-10 * u));
  set(p, Segment::forearm_r, ry(-10 * u));
}

void arm_raise(double t, double d, BodyPose& p) {
  const double part = d / 4;
  const int k = std::min(3, static_cast<int>(t / part));
  const double u = bump((t - k * part) / part);
  switch (k) {
    case 0:  // both arms forward to 120 degrees of flexion (through 90: no singularity)
      set(p, Segment::upper_arm_l, ry(-120 * u));
      set(p, Segment::upper_arm_r, ry(-120 * u));
      break;
    case 1:  // both arms sideways to 110 degrees of abduction
      set(p, Segment::upper_arm_l, rx(110 * u));
      set(p, Segment::upper_arm_r, rx(-110 * u));
      break;
    case 2:  // left arm overhead (160 flexion), right arm abducted 95 with elbow bent
      set(p, Segment::upper_arm_l, ry(-160 * u));
      set(p, Segment::upper_arm_r, rx(-95 * u));
      set(p, Segment::forearm_r, ry(-60 * u));
      break;
    default:  // elbow curls (palms facing each other), wrists flexing
      // The palms face the body's midline, so wrist flexion is about x (left: -, right: +
      // mirrored) and the small deviation about y.
      set(p, Segment::forearm_l, ry(-130 * u));
      set(p, Segment::forearm_r, ry(-130 * u));
      set(p, Segment::hand_l, rx(-40 * u) * ry(-15 * u));
      set(p, Segment::hand_r, rx(40 * u) * ry(15 * u));
      break;
  }
}

/// The calibration moves after the N-pose (calibration_moves_s()): two shallow knee bends with
/// the elbows curling at the same time, standing in place: the knee and elbow flexion the hinge
/// refinement of the calibration identifies the segments' axes from.
void calibration_moves(double t, double d, BodyPose& p) {
  const double half = d / 2;
  const double u = bump(std::fmod(t, half) / half);
  p.q_earth_pelvis = ry(10 * u);
  leg(p, true, 45 * u, 60 * u, 10 * u);
  leg(p, false, 45 * u, 60 * u, 10 * u);
  set(p, Segment::forearm_l, ry(-90 * u));
  set(p, Segment::forearm_r, ry(-90 * u));
}

void reach(double t, double d, BodyPose& p) {
  const double half = d / 2;
  const bool right = t < half;
  const double tau = (right ? t : t - half) / half;
  const double u = bump(tau);
  const double side = right ? 1 : -1;  // reach across the body toward the other side
  set(p, Segment::torso, rz(20 * side * u) * ry(10 * u));
  set(p, right ? Segment::upper_arm_r : Segment::upper_arm_l, rz(25 * side * u) * ry(-75 * u));
  const double elbow = 25 * u + 60 * bump(2 * tau) + 60 * bump(2 * tau - 1);
  set(p, right ? Segment::forearm_r : Segment::forearm_l, ry(-elbow));
  set(p, right ? Segment::hand_r : Segment::hand_l, ry(-20 * u) * rz(10 * side * u));
  set(p, Segment::neck, rz(-10 * side * u) * ry(10 * u));
}

void clip_pose(const Clip& c, double t, BodyPose& p) {
  switch (c.kind) {
    case Clip::kStand:
      return stand(t, c.duration_s, p);
    case Clip::kWalk:
      return walk(t, c.duration_s, p);
    case Clip::kTurn:
      return turn(t, c.duration_s, c.yaw_change_deg, p);
    case Clip::kSquat:
      return squat(t, c.duration_s, p);
    case Clip::kArmRaise:
      return arm_raise(t, c.duration_s, p);
    case Clip::kReach:
      return reach(t, c.duration_s, p);
    case Clip::kCalibrationMoves:
      return calibration_moves(t, c.duration_s, p);
  }
}

/// Clips played one after another; the heading accumulates over turns.
class ClipSequence final : public Motion {
 public:
  /// calib_clip: index of the N-pose calibration stand (a kStand clip), or -1 for none.
  explicit ClipSequence(std::vector<Clip> clips, int calib_clip = 0)
      : clips_(std::move(clips)), calib_clip_(calib_clip) {
    double t = 0, yaw = 0;
    for (const Clip& c : clips_) {
      start_s_.push_back(t);
      yaw_before_deg_.push_back(yaw);
      t += c.duration_s;
      yaw += c.yaw_change_deg;
    }
    duration_s_ = t;
  }
  double duration_s() const override { return duration_s_; }
  std::pair<double, double> calibration_window_s() const override {
    if (calib_clip_ < 0 || clips_[calib_clip_].kind != Clip::kStand) return {0.0, 0.0};
    return {start_s_[calib_clip_], start_s_[calib_clip_] + clips_[calib_clip_].duration_s};
  }
  void pose(double t_s, BodyPose& out) const override {
    t_s = std::clamp(t_s, 0.0, duration_s_);
    size_t i = 0;
    while (i + 1 < clips_.size() && t_s >= start_s_[i + 1])
      ++i;
    out = BodyPose{};
    clip_pose(clips_[i], t_s - start_s_[i], out);
    out.q_earth_pelvis = rz(yaw_before_deg_[i]) * out.q_earth_pelvis;
  }

 private:
  std::vector<Clip> clips_;
  int calib_clip_;
  std::vector<double> start_s_, yaw_before_deg_;
  double duration_s_ = 0;
};

std::vector<Clip> calibration_procedure_clips() {
  return {{Clip::kStand, 3.0},
          {Clip::kCalibrationMoves, calibration_moves_s() - 1.0},
          {Clip::kStand, 1.0}};
}

bool is_bvh_path(std::string_view name) {
  if (name.size() < 4) return false;
  std::string ext(name.substr(name.size() - 4));
  for (char& ch : ext)
    ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return ext == ".bvh";
}

constexpr std::string_view kNames[] = {"npose",     "walk",  "turn",    "squat",
                                       "arm_raise", "reach", "sequence"};

}  // namespace

std::span<const std::string_view> motion_names() {
  return kNames;
}

std::unique_ptr<Motion> make_motion(std::string_view name) {
  // "session<S>+": a BVH clip played back and forth for at least S seconds. Only "session"
  // followed by a number's first character is the prefix ("session_take.bvh" is a file).
  constexpr std::string_view kSession = "session";
  double session_s = 0;
  if (name.starts_with(kSession) && name.size() > kSession.size() &&
      std::string_view("0123456789+-.").find(name[kSession.size()]) != std::string_view::npos) {
    const size_t plus = name.find('+');
    const std::string digits(name.substr(kSession.size(), plus - kSession.size()));
    char* end = nullptr;
    session_s = std::strtod(digits.c_str(), &end);
    if (plus == std::string_view::npos || digits.empty() || *end != '\0' || !(session_s > 0))
      throw std::invalid_argument("session<S>+ needs a positive number of seconds, not '" +
                                  std::string(name) + "'");
    name.remove_prefix(plus + 1);
    if (!is_bvh_path(name))
      throw std::invalid_argument("session<S>+ is for BVH clips, not '" + std::string(name) + "'");
  }
  std::vector<Clip> clips;
  // A motion after the calibration moves starts from where they end (its own N-pose stand
  // would be a second calibration stand: dropped).
  const auto append = [&clips](std::vector<Clip> more) {
    const bool after_moves = !clips.empty();
    for (size_t i = after_moves ? 1 : 0; i < more.size(); ++i)
      clips.push_back(more[i]);
  };
  const Clip calib{Clip::kStand, 3.0}, rest{Clip::kStand, 1.0};
  // "warmup+": the sensors have been on for a while before the calibration (the person put
  // them on and walked in: walk, turn, walk back, turn, stand), so the filters have seen motion.
  constexpr std::string_view kWarmup = "warmup+";
  std::vector<Clip> warmup;
  if (name.starts_with(kWarmup)) {
    name.remove_prefix(kWarmup.size());
    warmup = {rest,
              {Clip::kWalk, 6.6},
              {Clip::kTurn, 3.6, 180},
              {Clip::kWalk, 6.6},
              {Clip::kTurn, 3.6, 180},
              rest};
  }
  constexpr std::string_view kPrefix = "calibrate+";
  const bool calibrate = name.starts_with(kPrefix);
  if (calibrate) {
    name.remove_prefix(kPrefix.size());
    if (name.starts_with(kPrefix) || name.starts_with(kWarmup) || name == "npose")
      throw std::invalid_argument("calibrate+ needs a moving motion after it, not '" +
                                  std::string(name) + "'");
    clips = calibration_procedure_clips();
  }
  if (is_bvh_path(name)) {
    if (!warmup.empty()) throw std::invalid_argument("warmup+ is for the built-in motions");
    // The file's own lead-in stand is the calibration stand unless the procedure comes first.
    return calibrate ? make_bvh_motion(std::string(name), 0.0, 1.0, make_calibration_procedure(),
                                       session_s)
                     : make_bvh_motion(std::string(name), 3.0, 1.0, nullptr, session_s);
  }
  if (name == "npose") {
    append({{Clip::kStand, 5.0}});
  } else if (name == "walk") {
    append({calib, {Clip::kWalk, 8.8}, rest});
  } else if (name == "turn") {
    append({calib, {Clip::kTurn, 4.5, 180}, rest});
  } else if (name == "squat") {
    append({calib, {Clip::kSquat, 6.0}, rest});
  } else if (name == "arm_raise") {
    append({calib, {Clip::kArmRaise, 12.0}, rest});
  } else if (name == "reach") {
    append({calib, {Clip::kReach, 6.0}, rest});
  } else if (name == "sequence") {
    append({calib,
            {Clip::kWalk, 6.6},
            {Clip::kTurn, 3.6, 180},
            {Clip::kWalk, 6.6},
            {Clip::kTurn, 3.6, 180},
            {Clip::kSquat, 6.0},
            {Clip::kArmRaise, 12.0},
            {Clip::kReach, 6.0},
            rest});
  } else {
    std::string valid;
    for (auto n : kNames)
      valid += (valid.empty() ? "" : ", ") + std::string(n);
    throw std::invalid_argument("unknown motion '" + std::string(name) + "' (valid: " + valid +
                                " or a BVH file path ending in .bvh, each optionally prefixed by "
                                "calibrate+)");
  }
  const int calib_clip = static_cast<int>(warmup.size());
  clips.insert(clips.begin(), warmup.begin(), warmup.end());
  return std::make_unique<ClipSequence>(std::move(clips), calib_clip);
}

std::unique_ptr<Motion> make_calibration_procedure() {
  return std::make_unique<ClipSequence>(calibration_procedure_clips());
}

double calibration_moves_s() {
  return 5.0;
}

}  // namespace mocap::sim
