#pragma once
// Number and JSON formatting shared by the result writers and the commands: lengths with 9 decimals (nm), unit vectors with 12.

#include <charconv>
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
// `precision` decimals, correctly rounded as printf's %.Nf (std::to_chars is specified to give printf's text, and
// is several times faster: a million-row output writes 7 million of these), appended to `out`: writers of many rows
// need no string per number.
inline std::string& append_fixed(std::string& out, double v, int precision) {
  char buf[400];  // |v| up to 1.8e308 written out in full, and the decimals
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v + 0.0, std::chars_format::fixed, precision);
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

inline std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt("\\u%04x", static_cast<unsigned char>(c));
      continue;
    }
    out += c;
  }
  return out + "\"";
}

}  // namespace probecomp::io
