#include "probecomp/io/json.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <string>

#include "probecomp/io/format.hpp"

namespace probecomp::io {
namespace {

// The double nearest to the text `text` (the value as printf would print it): nlohmann/json then writes the
// shortest text that reads back as that double, which is that text. −0 becomes 0.
Json read_back(const std::string& text) {
  const double v = std::strtod(text.c_str(), nullptr);
  return v == 0.0 ? 0.0 : v;
}

}  // namespace

Json json_number(double value, int digits) {
  if (!std::isfinite(value)) return nullptr;
  char text[64];  // %.*g: at most 17 significant digits, a sign, a point and an exponent
  const auto [end, ec] = std::to_chars(text, text + sizeof text, value, std::chars_format::general, digits);
  return read_back(std::string(text, ec == std::errc() ? end : text));
}

Json json_fixed(double value, int decimals) {
  if (!std::isfinite(value)) return nullptr;
  return read_back(fixed(value, decimals));
}

std::string json_text(const Json& value, int indent) {
  return value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace probecomp::io
