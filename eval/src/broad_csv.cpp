// Parses BROAD-layout IMU CSVs (plain or gzip) with line-precise error messages.
#include "mocap/eval/broad_csv.hpp"

#include "mocap/core/imu_sample.hpp"
#include "mocap/core/units.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>

#ifndef MOCAP_BROAD_DIR
#define MOCAP_BROAD_DIR "../shared/datasets/broad"
#endif

namespace mocap {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

bool parse_double(std::string_view f, double& v) {
  f = trim(f);
  if (f.empty()) return false;
  if (f.front() == '+') f.remove_prefix(1);
  const char* end = f.data() + f.size();
  auto r = std::from_chars(f.data(), end, v);
  return r.ec == std::errc() && r.ptr == end;
}

// Rate from a comment like "# name, 285.714286 Hz, ...": the number before "Hz".
double rate_from_comment(std::string_view c) {
  const size_t hz = c.find("Hz");
  if (hz == std::string_view::npos) return 0;
  size_t e = hz;
  while (e > 0 && c[e - 1] == ' ')
    --e;
  size_t b = e;
  while (b > 0 && (std::isdigit(static_cast<unsigned char>(c[b - 1])) || c[b - 1] == '.'))
    --b;
  double v = 0;
  if (b == e || !parse_double(c.substr(b, e - b), v) || !(v > 0) || !std::isfinite(v)) return 0;
  return v;
}

std::string name_from_comment(std::string_view c) {
  c = trim(c.substr(1));
  const size_t comma = c.find(',');
  std::string_view n = trim(c.substr(0, comma));
  if (n.rfind("BROAD trial ", 0) == 0) n.remove_prefix(12);
  return std::string(n);
}

enum Col { kT, kGx, kGy, kGz, kAx, kAy, kAz, kMx, kMy, kMz, kRw, kRx, kRy, kRz, kMove, kNumCols };
constexpr std::array<std::string_view, kNumCols> kColNames = {
    "t",     "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z",   "mag_x",
    "mag_y", "mag_z", "ref_w", "ref_x", "ref_y", "ref_z", "movement"};

}  // namespace

bool parse_broad_csv(std::string_view text, BroadTrial& out, std::string& error) {
  out = BroadTrial{};
  std::array<int, kNumCols> col;
  col.fill(-1);
  bool have_header = false;
  size_t line_no = 0;
  int ncols = 0;
  std::array<double, kNumCols> v{};
  std::vector<std::string_view> fields;
  size_t pos = 0;
  auto fail = [&](const std::string& what) {
    error = "line " + std::to_string(line_no) + ": " + what;
    return false;
  };
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    std::string_view line = trim(text.substr(pos, nl - pos));
    pos = nl + 1;
    ++line_no;
    if (line.empty()) continue;
    if (line.front() == '#') {
      if (!have_header) {
        if (out.rate_hz == 0) out.rate_hz = rate_from_comment(line);
        if (out.name.empty()) out.name = name_from_comment(line);
      }
      continue;
    }
    fields.clear();
    size_t b = 0;
    while (true) {
      size_t c = line.find(',', b);
      fields.push_back(trim(line.substr(b, c == std::string_view::npos ? line.size() - b : c - b)));
      if (c == std::string_view::npos) break;
      b = c + 1;
    }
    if (!have_header) {
      for (size_t i = 0; i < fields.size(); ++i)
        for (int k = 0; k < kNumCols; ++k)
          if (fields[i] == kColNames[k]) {
            if (col[k] >= 0) return fail("column '" + std::string(kColNames[k]) + "' repeated");
            col[k] = static_cast<int>(i);
          }
      for (int k = kT; k <= kAz; ++k)
        if (col[k] < 0)
          return fail("header lacks required column '" + std::string(kColNames[k]) +
                      "' (need t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z)");
      out.has_mag = col[kMx] >= 0 && col[kMy] >= 0 && col[kMz] >= 0;
      out.has_ref = col[kRw] >= 0 && col[kRx] >= 0 && col[kRy] >= 0 && col[kRz] >= 0;
      out.has_movement = col[kMove] >= 0;
      ncols = static_cast<int>(fields.size());
      have_header = true;
      continue;
    }
    if (static_cast<int>(fields.size()) != ncols)
      return fail("expected " + std::to_string(ncols) + " fields, found " +
                  std::to_string(fields.size()));
    for (int k = 0; k < kNumCols; ++k) {
      if (col[k] < 0) {
        v[k] = 0;
        continue;
      }
      if (!parse_double(fields[col[k]], v[k]))
        return fail("column " + std::to_string(col[k] + 1) + " ('" + std::string(kColNames[k]) +
                    "'): not a number: '" + std::string(fields[col[k]].substr(0, 40)) + "'");
    }
    if (!std::isfinite(v[kT])) return fail("time 't' is not finite");
    if (!out.t_s.empty() && !(v[kT] > out.t_s.back()))
      return fail("time 't' does not increase (" + std::string(fields[col[kT]]) + ")");
    out.t_s.push_back(v[kT]);
    // Non-finite sensor values are kept: the filters reject and count them.
    out.gyr_rad_s.emplace_back(v[kGx], v[kGy], v[kGz]);
    out.acc_m_s2.emplace_back(v[kAx], v[kAy], v[kAz]);
    if (out.has_mag) out.mag_uT.emplace_back(v[kMx], v[kMy], v[kMz]);
    if (out.has_ref) out.ref_wxyz.emplace_back(v[kRw], v[kRx], v[kRy], v[kRz]);
    if (out.has_movement) out.movement.push_back(v[kMove] != 0 ? 1 : 0);
  }
  if (!have_header) {
    line_no = std::max<size_t>(line_no, 1);
    return fail("no header line (expected t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,...)");
  }
  if (out.t_s.empty()) return fail("no samples after the header");
  if (out.rate_hz == 0 && out.t_s.size() > 1)
    out.rate_hz = static_cast<double>(out.t_s.size() - 1) / (out.t_s.back() - out.t_s.front());
  return true;
}

bool read_broad_csv(const std::string& path, BroadTrial& out, std::string& error) {
  gzFile f = gzopen(path.c_str(), "rb");  // reads plain files transparently
  if (!f) {
    error = path + ": cannot open";
    return false;
  }
  std::string text;
  std::array<char, 1 << 16> buf;
  while (true) {
    const int n = gzread(f, buf.data(), static_cast<unsigned>(buf.size()));
    if (n < 0) {
      int errnum = 0;
      error = path + ": read error: " + gzerror(f, &errnum);
      gzclose(f);
      return false;
    }
    if (n == 0) break;
    text.append(buf.data(), static_cast<size_t>(n));
  }
  gzclose(f);
  if (!parse_broad_csv(text, out, error)) {
    error = path + ": " + error;
    return false;
  }
  if (out.name.empty()) out.name = std::filesystem::path(path).filename().string();
  return true;
}

std::vector<std::string> list_broad_trials(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    auto ends = [&](std::string_view s) {
      return n.size() >= s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0;
    };
    if (e.is_regular_file() && (ends(".csv") || ends(".csv.gz"))) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string default_broad_dir() {
  return MOCAP_BROAD_DIR;
}

size_t clip_gyro(BroadTrial& trial, double range_dps) {
  const double max_rad_s = range_dps * kRadPerDeg;
  trial.flags.resize(trial.size(), 0);
  size_t clipped = 0;
  for (size_t i = 0; i < trial.size(); ++i) {
    Eigen::Vector3d& g = trial.gyr_rad_s[i];
    if (g.cwiseAbs().maxCoeff() < max_rad_s) continue;
    g = g.cwiseMax(-max_rad_s).cwiseMin(max_rad_s);
    trial.flags[i] |= kFlagSaturated | kFlagGyrClipped;
    ++clipped;
  }
  return clipped;
}

}  // namespace mocap
