#pragma once
// Number formatting shared by the result writers and the commands: lengths with 9 decimals (nm), unit vectors with 12.

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

namespace probecomp::io {

inline std::string fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value + 0.0);  // + 0.0 turns −0 into 0
  return buf;
}
// The shortest text that reads back as the same double (std::to_chars): for files converted between formats, where
// a value must come back exactly.
inline std::string exact(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v + 0.0);
  return std::string(buf, ec == std::errc() ? end : buf);
}
// GCC's and Clang's 128-bit integers (__extension__: not ISO C++, which -Wpedantic would otherwise say).
__extension__ typedef unsigned __int128 Uint128;

// `precision` decimals of v in `buf` (at least 40 chars), correctly rounded as printf's %.Nf and std::to_chars
// round (half to even on v's exact binary value), when that is exact in integers: v = M·2^E (M < 2^53), so
// v·10^p = M·5^p·2^(E+p), and M·5^p (p ≤ 12: under 2^81) shifted right by −(E + p) bits is the digits, the bits
// shifted out deciding the rounding. The end of the text, or null where this does not apply (a shift left, a
// result of 2^63 or more, p > 12, not finite): then std::to_chars, whose fixed format is the slower part of writing a
// CSV (a million rows write 7 million numbers: the whole write 0.74 s with it alone, 0.40 s with this first).
inline char* fixed_chars(char* buf, double v, int precision) {
  if (precision < 0 || precision > 12 || !std::isfinite(v)) return nullptr;
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(v);
  const bool negative = (bits >> 63) != 0;
  const int exponent_field = static_cast<int>((bits >> 52) & 0x7ff);
  const std::uint64_t fraction = bits & ((std::uint64_t{1} << 52) - 1);
  const std::uint64_t M = exponent_field == 0 ? fraction : fraction | (std::uint64_t{1} << 52);
  const int E = exponent_field == 0 ? -1074 : exponent_field - 1075;
  const int shift = -(E + precision);
  if (shift <= 0) return nullptr;
  constexpr std::uint64_t kPowersOf5[13] = {1, 5, 25, 125, 625, 3125, 15625, 78125, 390625, 1953125, 9765625,
                                             48828125, 244140625};
  constexpr std::uint64_t kPowersOf10[13] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000,
                                             1000000000, 10000000000, 100000000000, 1000000000000};
  const Uint128 X = static_cast<Uint128>(M) * kPowersOf5[precision];
  std::uint64_t N = 0;
  if (shift < 128) {
    const Uint128 q = X >> shift;
    if (q >= (static_cast<Uint128>(1) << 63)) return nullptr;
    const Uint128 rest = X - (q << shift);
    const Uint128 half = static_cast<Uint128>(1) << (shift - 1);
    N = static_cast<std::uint64_t>(q);
    if (rest > half || (rest == half && (N & 1) != 0)) ++N;
  }
  const std::uint64_t scale = kPowersOf10[precision];
  char* at = buf;
  if (negative) *at++ = '-';  // printf's sign, also where the digits round to zero
  at = std::to_chars(at, at + 24, N / scale).ptr;
  if (precision > 0) {
    *at++ = '.';
    std::uint64_t decimals = N % scale;
    for (int k = precision - 1; k >= 0; --k) {
      at[k] = static_cast<char>('0' + decimals % 10);
      decimals /= 10;
    }
    at += precision;
  }
  return at;
}

// `precision` decimals, correctly rounded as printf's %.Nf, appended to `out`: writers of many rows need no string
// per number.
inline std::string& append_fixed(std::string& out, double v, int precision) {
  char buf[400];  // |v| up to 1.8e308 written out in full, and the decimals
  v += 0.0;       // −0 as 0
  if (char* end = fixed_chars(buf, v, precision)) return out.append(buf, end);
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, precision);
  return ec == std::errc() ? out.append(buf, end) : out.append(fmt("%f", v));
}
// The same as a string of its own.
inline std::string fixed(double v, int precision) {
  std::string out;
  append_fixed(out, v, precision);
  return out;
}
inline std::string mm(double v) { return fixed(v, 9); }
inline std::string unit(double v) { return fixed(v, 12); }

}  // namespace probecomp::io
