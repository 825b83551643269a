// to_chars_fixed writes exactly what std::to_chars(fixed, precision) writes: random doubles over
// many magnitudes, exact decimal ties (dyadic values such as 1/128 at 6 decimals), values that
// round to zero (negative ones keep their sign), subnormals, the fallback range and a short buffer.
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "mocap/core/fixed_chars.hpp"

namespace mocap {
namespace {

std::string expected(double v, int precision) {
  char b[400];
  const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::fixed, precision);
  return std::string(b, r.ptr);
}

std::string ours(double v, int precision) {
  char b[400];
  const auto r = to_chars_fixed(b, b + sizeof b, v, precision);
  EXPECT_EQ(r.ec, std::errc{});
  return std::string(b, r.ptr);
}

}  // namespace

TEST(FixedChars, SameCharactersAsToCharsForRandomValues) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> mag(-12, 17), uni(-1, 1);
  int checked = 0;
  for (int k = 0; k < 300000; ++k) {
    const double v = uni(rng) * std::pow(10.0, mag(rng));
    const int precision = static_cast<int>(rng() % 10);
    ASSERT_EQ(ours(v, precision), expected(v, precision)) << v << " at " << precision;
    ++checked;
  }
  EXPECT_EQ(checked, 300000);
}

TEST(FixedChars, IntegerPartsAcrossTheirDigitCounts) {
  // The integer part is written from a table below 1000, by std::to_chars above: each width,
  // and values that round up into the next one.
  for (const double v : {0.0, 9.0, 9.9999996, 10.0, 99.5, 99.9999996, 100.0, 999.25, 999.9999996,
                         1000.0, 1234.5, -7.25, -99.9999996, -999.9999996, 180.0, -179.999999})
    for (int precision = 0; precision <= 9; ++precision)
      EXPECT_EQ(ours(v, precision), expected(v, precision)) << v << " at " << precision;
}

TEST(FixedChars, TiesRoundToEvenAndSignsStay) {
  // Dyadic values whose decimal expansion ends exactly half-way at the precision asked for.
  for (int precision = 0; precision <= 9; ++precision)
    for (int e = 1; e <= 40; ++e)
      for (int m = -300; m <= 300; ++m) {
        const double v = std::ldexp(static_cast<double>(m), -e);
        ASSERT_EQ(ours(v, precision), expected(v, precision)) << v << " at " << precision;
      }
  for (const double v : {0.0, -0.0, 1e-300, -1e-300, 4.9e-324, -4.9e-324, 0.0078125, -0.0078125,
                         0.5, -0.5, 1.5, 2.5, 1e15, -1e15, 9007199254740991.0, 1e18, 1e300})
    for (int precision = 0; precision <= 9; ++precision)
      EXPECT_EQ(ours(v, precision), expected(v, precision)) << v << " at " << precision;
  EXPECT_EQ(ours(-1e-9, 6), "-0.000000");
  EXPECT_EQ(ours(0.0078125, 6), "0.007812");  // a tie: to the even digit
}

TEST(FixedChars, NonFiniteValuesAndShortBuffersAreLeftToToChars) {
  for (const double v :
       {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
        std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(ours(v, 3), expected(v, 3));
  char b[4];
  EXPECT_EQ(to_chars_fixed(b, b + sizeof b, 12345.678, 2).ec, std::errc::value_too_large);
  const auto r = to_chars_fixed(b, b + sizeof b, 1.25, 1);
  ASSERT_EQ(r.ec, std::errc{});
  EXPECT_EQ(std::string(b, r.ptr), "1.2");
}

}  // namespace mocap
