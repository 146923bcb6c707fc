// Fixed-point text against std::to_chars (the standard's own correctly rounded %.Nf): random values at every
// magnitude, exact ties (half to even), their neighbours, zeros, subnormals, and values past the fast path.

#include "probecomp/io/format.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace probecomp::io {
namespace {

std::string reference(double v, int precision) {
  char buf[400];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v + 0.0, std::chars_format::fixed, precision);
  return ec == std::errc() ? std::string(buf, end) : "error";
}

// Every value as append_fixed writes it and as to_chars does; returns how many took the fast path.
int expect_as_to_chars(const std::vector<double>& values, int precision) {
  int fast = 0;
  for (const double v : values) {
    char buf[64];
    fast += fixed_chars(buf, v + 0.0, precision) != nullptr;
    std::string out;
    append_fixed(out, v, precision);
    EXPECT_EQ(out, reference(v, precision)) << "v = " << std::hexfloat << v << ", " << precision << " decimals";
    if (::testing::Test::HasFailure()) break;
  }
  return fast;
}

TEST(Format, FixedDecimalsAreToCharsText) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coordinate(-2e4, 2e4), exponent(-16.0, 10.0);
  std::vector<double> values;
  for (int k = 0; k < 300000; ++k) values.push_back(coordinate(rng));
  for (int k = 0; k < 300000; ++k) values.push_back((k % 2 ? -1.0 : 1.0) * std::pow(10.0, exponent(rng)));
  for (const int precision : {0, 1, 3, 6, 9, 12}) {
    SCOPED_TRACE(precision);
    const int fast = expect_as_to_chars(values, precision);
    EXPECT_GT(fast, static_cast<int>(values.size() * 9 / 10));  // the fast path is the one taken
  }
}

TEST(Format, TiesRoundHalfToEvenAndTheirNeighboursAway) {
  for (const int precision : {0, 3, 9, 12}) {
    SCOPED_TRACE(precision);
    // odd / 2^(p + 1) · 10^−p ... v·10^p = odd·5^p / 2 is an exact tie when v = odd / 2^(p+1): written exactly.
    std::vector<double> values;
    for (long odd = 1; odd < 4001; odd += 2) {
      const double tie = std::ldexp(static_cast<double>(odd), -(precision + 1));
      for (const double v : {tie, -tie, std::nextafter(tie, 0.0), std::nextafter(tie, 1e300), 1000.0 + tie}) values.push_back(v);
    }
    expect_as_to_chars(values, precision);
  }
}

TEST(Format, ZerosSubnormalsAndValuesPastTheFastPath) {
  const double tiny = std::numeric_limits<double>::denorm_min();
  const std::vector<double> values = {0.0,     -0.0,     tiny,    -tiny,  1e-300, -1e-300, -1e-13, 4e-10, -4e-10,
                                      9.2e9,   -9.2e9,   9.3e9,   1e15,   -1e15,  4.5e18,  1e300,  -1e300,
                                      std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity(),
                                      -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()};
  for (const int precision : {0, 9, 12, 15}) {
    SCOPED_TRACE(precision);
    expect_as_to_chars(values, precision);
  }
  // −0 is written as 0.
  std::string out;
  append_fixed(out, -0.0, 3);
  EXPECT_EQ(out, "0.000");
}

}  // namespace
}  // namespace probecomp::io
