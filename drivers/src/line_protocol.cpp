// DIY line-protocol parser, units declarations and line formatting (see line_protocol.hpp).
#include "mocap/drivers/line_protocol.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "mocap/core/units.hpp"

namespace mocap::line {

static bool is_sep(char c) {
  return c == ' ' || c == ',' || c == '\t' || c == ';';
}

static int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool Parser::parse_line(Record& out) {
  std::string_view s(buf_.data(), n_);
  while (!s.empty() && (s.back() == '\r' || s.back() == ' '))
    s.remove_suffix(1);
  while (!s.empty() && s.front() == ' ')
    s.remove_prefix(1);
  if (s.empty()) return false;
  if (s.front() == '#') {
    constexpr std::string_view kUnitsTag = "#units";
    if (s.substr(0, kUnitsTag.size()) != kUnitsTag) return false;  // a comment
    out.kind = Record::kUnits;
    out.header = s.substr(kUnitsTag.size());
    ++frames;
    return true;
  }
  const auto star = s.rfind('*');
  if (star != std::string_view::npos) {
    const auto cs = s.substr(star + 1);
    uint8_t x = 0;
    for (char c : s.substr(0, star))
      x ^= static_cast<uint8_t>(c);
    if (cs.size() != 2 || hex_value(cs[0]) < 0 || hex_value(cs[1]) < 0 ||
        x != hex_value(cs[0]) * 16 + hex_value(cs[1])) {
      ++checksum_errors;
      return false;
    }
    s = s.substr(0, star);
  }
  double vals[10];
  int n = 0;
  const char* p = s.data();
  const char* end = s.data() + s.size();
  while (p < end) {
    while (p < end && is_sep(*p))
      ++p;
    if (p == end) break;
    if (n == 10) return ++resyncs, false;
    const auto r = std::from_chars(p, end, vals[n]);
    if (r.ec != std::errc() || !std::isfinite(vals[n]) || (r.ptr < end && !is_sep(*r.ptr)))
      return ++resyncs, false;
    p = r.ptr;
    ++n;
  }
  if (n != 10) return ++resyncs, false;
  out.kind = Record::kSample;
  out.t = vals[0];
  for (int k = 0; k < 9; ++k)
    out.v[k] = vals[k + 1];
  ++frames;
  return true;
}

std::size_t Parser::consume(std::span<const uint8_t> in, Record& out, bool& got) {
  got = false;
  std::size_t i = 0;
  while (i < in.size()) {
    const char c = static_cast<char>(in[i++]);
    if (c == '\n') {
      const bool was_overflow = overflow_;
      overflow_ = false;
      if (!was_overflow) got = parse_line(out);
      n_ = 0;
      if (got) return i;
      continue;
    }
    if (overflow_) continue;
    if (n_ == kMaxLine || c == '\0') {  // not a text line: skip to the next newline
      overflow_ = true;
      ++resyncs;
      continue;
    }
    buf_[n_++] = c;
  }
  return i;
}

static bool unit_factor(std::string_view key, std::string_view v, Units& u) {
  if (key == "t") {
    if (v == "ns") return u.t_to_ns = 1, true;
    if (v == "us") return u.t_to_ns = 1e3, true;
    if (v == "ms") return u.t_to_ns = 1e6, true;
    if (v == "s") return u.t_to_ns = 1e9, true;
  } else if (key == "acc") {
    if (v == "g") return u.acc_to_m_s2 = 9.80665, true;
    if (v == "mg") return u.acc_to_m_s2 = 9.80665e-3, true;
    if (v == "m/s2") return u.acc_to_m_s2 = 1, true;
  } else if (key == "gyr") {
    if (v == "dps") return u.gyr_to_rad_s = kRadPerDeg, true;
    if (v == "mdps") return u.gyr_to_rad_s = M_PI / 180e3, true;
    if (v == "rad/s") return u.gyr_to_rad_s = 1, true;
  } else if (key == "mag") {
    if (v == "uT") return u.mag_to_uT = 1, true;
    if (v == "nT") return u.mag_to_uT = 1e-3, true;
    if (v == "mG") return u.mag_to_uT = 0.1, true;
    if (v == "G" || v == "gauss") return u.mag_to_uT = 100, true;
  } else if (key == "wrap") {
    int bits = 0;
    const auto r = std::from_chars(v.data(), v.data() + v.size(), bits);
    if (r.ec == std::errc() && r.ptr == v.data() + v.size() && bits >= 8 && bits <= 64)
      return u.wrap_bits = bits, true;
  }
  return false;
}

bool parse_units(std::string_view decl, Units& units, std::string& err) {
  Units u = units;
  std::size_t pos = 0;
  while (pos < decl.size()) {
    while (pos < decl.size() && is_sep(decl[pos]))
      ++pos;
    std::size_t end = pos;
    while (end < decl.size() && !is_sep(decl[end]))
      ++end;
    if (end == pos) break;
    const auto tok = decl.substr(pos, end - pos);
    const auto eq = tok.find('=');
    if (eq == std::string_view::npos || !unit_factor(tok.substr(0, eq), tok.substr(eq + 1), u)) {
      err = "line protocol: unknown units declaration \"" + std::string(tok) +
            "\" (expected t=ns|us|ms|s acc=g|mg|m/s2 gyr=dps|mdps|rad/s mag=uT|nT|mG|G "
            "wrap=8..64)";
      return false;
    }
    pos = end;
  }
  units = u;
  return true;
}

std::string format_line(uint64_t t, const std::array<double, 9>& v, bool checksum) {
  char buf[kMaxLine];
  int n = std::snprintf(buf, sizeof buf, "%llu", static_cast<unsigned long long>(t));
  for (double x : v)
    n += std::snprintf(buf + n, sizeof buf - n, " %.6g", x);
  std::string s(buf, n);
  if (checksum) {
    uint8_t x = 0;
    for (char c : s)
      x ^= static_cast<uint8_t>(c);
    char cs[5];
    std::snprintf(cs, sizeof cs, "*%02X", x);
    s += cs;
  }
  s += '\n';
  return s;
}

}  // namespace mocap::line
