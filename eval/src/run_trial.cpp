// Drives the selected algorithm sample by sample over a BROAD-layout trial.
#include "mocap/eval/run_trial.hpp"

#include <cmath>

#include "mocap/eval/madgwick.hpp"
#include "mocap/eval/mahony.hpp"

namespace mocap {

std::optional<FilterAlgorithm> parse_filter_algorithm(std::string_view name) {
  if (name == "ours") return FilterAlgorithm::kDefault;
  for (FilterAlgorithm a :
       {FilterAlgorithm::kDefault, FilterAlgorithm::kMadgwick, FilterAlgorithm::kMahony})
    if (name == filter_algorithm_name(a)) return a;
  return std::nullopt;
}

std::optional<FilterMode> parse_filter_mode(std::string_view name) {
  if (name == "9d" || name == "9D") return FilterMode::k9d;
  if (name == "6d" || name == "6D") return FilterMode::k6d;
  return std::nullopt;
}

const char* filter_algorithm_name(FilterAlgorithm a) {
  switch (a) {
    case FilterAlgorithm::kDefault:
      return "default";
    case FilterAlgorithm::kMadgwick:
      return "madgwick";
    case FilterAlgorithm::kMahony:
      return "mahony";
  }
  return "?";
}

ImuSample trial_sample(const BroadTrial& trial, size_t i, FilterMode mode) {
  ImuSample s;
  s.t_host_ns = static_cast<int64_t>(std::llround(trial.t_s[i] * 1e9));
  s.t_device_ns = s.t_host_ns;
  s.seq = static_cast<uint32_t>(i);
  s.valid = kFieldGyr | kFieldAcc;
  if (i < trial.flags.size()) s.flags = trial.flags[i];
  s.gyr_rad_s = trial.gyr_rad_s[i];
  s.acc_m_s2 = trial.acc_m_s2[i];
  if (mode == FilterMode::k9d && trial.has_mag) {
    s.valid |= kFieldMag;
    s.mag_uT = trial.mag_uT[i];
  }
  return s;
}

namespace {

template <class F>
void drive(F& f, const BroadTrial& trial, FilterMode mode, std::vector<Eigen::Quaterniond>& out) {
  out.resize(trial.size());
  for (size_t i = 0; i < trial.size(); ++i) {
    f.update(trial_sample(trial, i, mode));
    out[i] = f.q_earth_sensor();
  }
}

/// A baseline (Madgwick, Mahony) with its default parameters, its magnetometer on in 9D.
template <class Filter, class Params>
void drive_baseline(const BroadTrial& trial, FilterMode mode,
                    std::vector<Eigen::Quaterniond>& out) {
  Params p;
  p.use_mag = mode == FilterMode::k9d;
  Filter f(p);
  drive(f, trial, mode, out);
}

}  // namespace

void run_trial(const BroadTrial& trial, FilterAlgorithm alg, FilterMode mode,
               const FilterParams& params, std::vector<Eigen::Quaterniond>& out) {
  switch (alg) {
    case FilterAlgorithm::kDefault: {
      const bool mag = mode == FilterMode::k9d;
      AttitudeFilter f(params);
      out.resize(trial.size());
      for (size_t i = 0; i < trial.size(); ++i) {
        f.update(trial_sample(trial, i, mode));
        const FilterOutput o = f.output();
        out[i] = mag ? o.q_earth_sensor : o.q_earth_sensor_6d;
      }
      return;
    }
    case FilterAlgorithm::kMadgwick:
      drive_baseline<MadgwickFilter, MadgwickParams>(trial, mode, out);
      return;
    case FilterAlgorithm::kMahony:
      drive_baseline<MahonyFilter, MahonyParams>(trial, mode, out);
      return;
  }
}

}  // namespace mocap
