// to_chars_fixed: a double in fixed notation with 0..9 decimals, the very characters of
// std::to_chars(first, last, v, std::chars_format::fixed, precision) (the exact binary value
// correctly rounded, ties to even, "-" on every negative value, -0 included), several times
// faster for the values poses are made of: exact integer arithmetic on the double's mantissa
// instead of a general shortest/precision algorithm. Hand-written because the text outputs
// (BVH export, the JSON pose stream) format tens of numbers per frame (bench replay: 22 M).
// Values beyond 2^63 / 10^precision, NaN and infinities go to std::to_chars.
#pragma once

#include <charconv>
#include <cstdint>
#include <cstring>

namespace mocap {

namespace fixed_chars_detail {
__extension__ typedef unsigned __int128 U128;  // GCC and Clang; exact 53 x 30-bit products
}  // namespace fixed_chars_detail

inline std::to_chars_result to_chars_fixed(char* first, char* last, double v, int precision) {
  constexpr uint64_t kPow10[] = {1,      10,      100,      1000,      10000,
                                 100000, 1000000, 10000000, 100000000, 1000000000};
  if (precision < 0 || precision > 9)
    return std::to_chars(first, last, v, std::chars_format::fixed, precision);
  uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  const bool negative = (bits >> 63) != 0;
  const int biased_exp = static_cast<int>((bits >> 52) & 0x7FF);
  uint64_t mantissa = bits & ((uint64_t{1} << 52) - 1);
  if (biased_exp == 0x7FF)
    return std::to_chars(first, last, v, std::chars_format::fixed, precision);
  int exp = -1074;  // v = mantissa * 2^exp
  if (biased_exp != 0) {
    mantissa |= uint64_t{1} << 52;
    exp = biased_exp - 1075;
  }
  if (exp >= 0 && mantissa != 0)  // an integer of 2^52 or more: not a pose's value
    return std::to_chars(first, last, v, std::chars_format::fixed, precision);
  // q = v * 10^precision rounded to the nearest integer, ties to even, exactly.
  uint64_t q = 0;
  const int shift = -exp;
  if (mantissa != 0 && shift <= 120) {
    using fixed_chars_detail::U128;
    const U128 n = static_cast<U128>(mantissa) * kPow10[precision];
    const U128 whole = n >> shift;
    if ((whole >> 63) != 0)
      return std::to_chars(first, last, v, std::chars_format::fixed, precision);
    q = static_cast<uint64_t>(whole);
    const U128 rest = n - (whole << shift);
    const U128 half = static_cast<U128>(1) << (shift - 1);
    if (rest > half || (rest == half && (q & 1) != 0)) ++q;
  }  // else |v| < 2^-67: below half of the last decimal, q = 0
  // Sign, integer part, point, fraction zero-padded: at most 1 + 19 + 1 + 9 characters.
  if (last - first < 1 + 19 + 1 + precision)
    return std::to_chars(first, last, v, std::chars_format::fixed, precision);
  char* p = first;
  if (negative) *p++ = '-';
  // Digits two at a time from a table (a pose's integer part is below 1000).
  static constexpr char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
      "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
      "8081828384858687888990919293949596979899";
  const uint64_t scale = kPow10[precision];
  const uint64_t whole = q / scale;
  if (whole < 10) {
    *p++ = static_cast<char>('0' + whole);
  } else if (whole < 100) {
    std::memcpy(p, kPairs + 2 * whole, 2);
    p += 2;
  } else if (whole < 1000) {
    *p++ = static_cast<char>('0' + whole / 100);
    std::memcpy(p, kPairs + 2 * (whole % 100), 2);
    p += 2;
  } else {
    p = std::to_chars(p, last, whole).ptr;
  }
  if (precision > 0) {
    *p++ = '.';
    uint64_t frac = q % scale;
    char* d = p + precision;
    int left = precision;
    for (; left >= 2; left -= 2) {
      d -= 2;
      std::memcpy(d, kPairs + 2 * (frac % 100), 2);
      frac /= 100;
    }
    if (left == 1) *--d = static_cast<char>('0' + frac);
    p += precision;
  }
  return {p, std::errc{}};
}

}  // namespace mocap
