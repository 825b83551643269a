// Strict line-by-line parser for CSV sample files (see sample_csv.hpp).
#include "mocap/daemon/sample_csv.hpp"
#include "mocap/core/text_check.hpp"

#include <charconv>
#include <cmath>

namespace mocap::daemon {

namespace {

constexpr std::string_view kFields[] = {"t",     "sensor", "gyr_x", "gyr_y", "gyr_z", "acc_x",
                                        "acc_y", "acc_z",  "mag_x", "mag_y", "mag_z"};
constexpr int kFieldCount = 11;
constexpr size_t kMaxLine = 4096;

bool parse_double(std::string_view s, double& out) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const char* end = s.data() + s.size();
  auto [p, ec] = std::from_chars(s.data(), end, out);
  return ec == std::errc() && p == end && std::isfinite(out);
}

}  // namespace

int SampleCsvParser::fail(std::string msg) {
  error_ = source_ + ":" + std::to_string(line_) + ": " + std::move(msg);
  return -1;
}

int SampleCsvParser::feed_line(std::string_view line, ImuSample& out) {
  ++line_;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.size() > kMaxLine)
    return fail("line longer than " + std::to_string(kMaxLine) + " bytes");
  if (trim_blanks(line).empty() || trim_blanks(line).front() == '#') return 0;
  cells_.clear();
  for (size_t i = 0;;) {
    const size_t j = line.find(',', i);
    cells_.push_back(
        trim_blanks(line.substr(i, j == std::string_view::npos ? std::string_view::npos : j - i)));
    if (j == std::string_view::npos) break;
    i = j + 1;
    if (cells_.size() > 64) return fail("too many columns");
  }
  if (!have_header_) {
    col_of_field_.assign(kFieldCount, -1);
    for (size_t c = 0; c < cells_.size(); ++c) {
      int f = -1;
      for (int k = 0; k < kFieldCount; ++k)
        if (cells_[c] == kFields[k]) f = k;
      if (f < 0)
        return fail("unknown column '" + std::string(cells_[c].substr(0, 32)) +
                    "' (expected t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z)");
      if (col_of_field_[f] >= 0)
        return fail("column '" + std::string(kFields[f]) + "' given twice");
      col_of_field_[f] = static_cast<int>(c);
    }
    for (int k = 0; k < 8; ++k)
      if (col_of_field_[k] < 0) return fail("missing column '" + std::string(kFields[k]) + "'");
    const int mags = (col_of_field_[8] >= 0) + (col_of_field_[9] >= 0) + (col_of_field_[10] >= 0);
    if (mags != 0 && mags != 3) return fail("give all of mag_x, mag_y, mag_z or none");
    columns_ = static_cast<int>(cells_.size());
    have_header_ = true;
    return 0;
  }
  if (static_cast<int>(cells_.size()) != columns_)
    return fail("expected " + std::to_string(columns_) + " columns, found " +
                std::to_string(cells_.size()));
  out = ImuSample{};
  double t_s = 0;
  if (!parse_double(cells_[col_of_field_[0]], t_s) || t_s < 0 || t_s > 1e7)
    return fail("column 't': '" + std::string(cells_[col_of_field_[0]].substr(0, 32)) +
                "' is not a time in seconds (0..1e7)");
  const std::string_view name = cells_[col_of_field_[1]];
  if (name.empty() || name.size() > 23)
    return fail("column 'sensor': needs a name of 1-23 characters");
  int id = -1;
  for (size_t i = 0; i < sensors_.size(); ++i)
    if (sensors_[i] == name) id = static_cast<int>(i);
  if (id < 0) {
    if (sensors_.size() >= 64) return fail("more than 64 sensors");
    sensors_.emplace_back(name);
    last_t_ns_.push_back(INT64_MIN);
    id = static_cast<int>(sensors_.size()) - 1;
  }
  double v[9];
  bool mag_present = col_of_field_[8] >= 0;
  if (mag_present) {
    const int empty = cells_[col_of_field_[8]].empty() + cells_[col_of_field_[9]].empty() +
                      cells_[col_of_field_[10]].empty();
    if (empty == 3)
      mag_present = false;
    else if (empty != 0)
      return fail("mag_x, mag_y, mag_z must all be given or all be empty");
  }
  for (int k = 0; k < 9; ++k) {
    if (k >= 6 && !mag_present) {
      v[k] = 0;
      continue;
    }
    const std::string_view cell = cells_[col_of_field_[2 + k]];
    if (!parse_double(cell, v[k]))
      return fail("column '" + std::string(kFields[2 + k]) + "': '" +
                  std::string(cell.substr(0, 32)) + "' is not a finite number");
  }
  const int64_t t_ns = static_cast<int64_t>(std::llround(t_s * 1e9));
  if (t_ns < last_any_t_ns_) return fail("time goes backwards (rows must be in time order)");
  if (t_ns <= last_t_ns_[id] && last_t_ns_[id] != INT64_MIN)
    return fail("sensor '" + std::string(name) + "': two samples at the same time");
  last_t_ns_[id] = t_ns;
  last_any_t_ns_ = t_ns;
  out.t_host_ns = t_ns;
  out.t_device_ns = t_ns;
  out.sensor_id = static_cast<uint16_t>(id);
  out.valid = kFieldGyr | kFieldAcc | (mag_present ? kFieldMag : 0);
  out.gyr_rad_s = {v[0], v[1], v[2]};
  out.acc_m_s2 = {v[3], v[4], v[5]};
  out.mag_uT = {v[6], v[7], v[8]};
  return 1;
}

}  // namespace mocap::daemon
