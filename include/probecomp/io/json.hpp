#pragma once
// JSON files are written with nlohmann/json (Debian's nlohmann-json3-dev): keys in the order they are set
// (ordered_json), each number to the digits its quantity carries, a value that is not finite as null.
#include <string>

#include <nlohmann/json.hpp>

namespace probecomp::io {

using Json = nlohmann::ordered_json;

// `value` to `digits` significant digits (printf's %.*g, read back): a double's 17 digits would claim more than a
// measured figure carries. Not finite → null: JSON has neither NaN nor infinity.
[[nodiscard]] Json json_number(double value, int digits = 9);

// `value` to `decimals` places after the point (printf's %.*f, read back); not finite → null.
[[nodiscard]] Json json_fixed(double value, int decimals);

// The text of a JSON file, ending in a newline: indented by `indent` spaces (compact when negative). Bytes that are
// not UTF-8 (a face name from an old IGES file) become U+FFFD rather than stopping the write.
[[nodiscard]] std::string json_text(const Json& value, int indent = 2);

}  // namespace probecomp::io
