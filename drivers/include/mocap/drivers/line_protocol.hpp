// The DIY line protocol (Arduino/ESP32 over serial or UDP), described in docs/devices.md:
//   "#units t=us acc=g gyr=dps mag=uT wrap=32"   header declaring units (optional, repeatable)
//   "<t> <ax> <ay> <az> <gx> <gy> <gz> <mx> <my> <mz>[*HH]"   one sample per line
// Fields are separated by spaces, commas or tabs; *HH is an optional XOR checksum (hex) of the
// characters before '*'. This file is the pure parser: bytes in, text values out (no units).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace mocap::line {

constexpr std::size_t kMaxLine = 200;

/// One parsed line: either a sample (time as declared + nine values) or a units header.
struct Record {
  enum Kind { kSample, kUnits } kind = kSample;
  double t = 0;               ///< time field, in the declared time unit
  std::array<double, 9> v{};  ///< ax ay az gx gy gz mx my mz, in the declared units
  std::string_view header;    ///< for kUnits: the text after "#units" (valid until next call)
};

/// Splits the stream into lines and parses them. Lines that are too long, have the wrong
/// number of fields, non-finite or malformed numbers, or a bad checksum are counted and dropped.
class Parser {
 public:
  std::size_t consume(std::span<const uint8_t> in, Record& out, bool& got);
  uint64_t frames = 0, checksum_errors = 0, resyncs = 0;

 private:
  bool parse_line(Record& out);
  std::array<char, kMaxLine> buf_{};
  std::size_t n_ = 0;
  bool overflow_ = false;
};

/// Units a device declares; defaults match docs/devices.md.
struct Units {
  double t_to_ns = 1e3;                        ///< "t=us"
  double acc_to_m_s2 = 9.80665;                ///< "acc=g"
  double gyr_to_rad_s = 0.017453292519943295;  ///< "gyr=dps"
  double mag_to_uT = 1.0;                      ///< "mag=uT"
  int wrap_bits = 32;  ///< the time field wraps at 2^wrap_bits (Arduino micros())
};
/// Applies "key=value ..." declarations to units; returns false and names the problem in err.
bool parse_units(std::string_view decl, Units& units, std::string& err);

/// Formats one sample line (with checksum) as a device would; used by simulators.
std::string format_line(uint64_t t, const std::array<double, 9>& v, bool checksum);

}  // namespace mocap::line
