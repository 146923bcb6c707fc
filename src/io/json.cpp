#include "probecomp/io/json.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace probecomp::io {
namespace {

// The double nearest to `value` printed with `format` (strtod of printf's text): nlohmann/json then writes the
// shortest text that reads back as that double, which is the text printf gave.
Json rounded(const char* format, int precision, double value) {
  if (!std::isfinite(value)) return nullptr;
  char text[64];
  std::snprintf(text, sizeof text, format, precision, value);
  const double v = std::strtod(text, nullptr);
  return v == 0.0 ? 0.0 : v;  // no "-0.0"
}

}  // namespace

Json json_number(double value, int digits) { return rounded("%.*g", digits, value); }

Json json_fixed(double value, int decimals) { return rounded("%.*f", decimals, value); }

std::string json_text(const Json& value, int indent) {
  return value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace probecomp::io
