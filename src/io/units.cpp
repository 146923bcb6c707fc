#include "probecomp/io/units.hpp"

#include "probecomp/io/text.hpp"

namespace probecomp::io {

std::optional<LengthUnit> length_unit(std::string_view name) {
  const std::string n = lower(std::string(name));
  if (n == "mm") return kMillimetre;
  if (n == "cm") return LengthUnit{"cm", 10.0};
  if (n == "meter") return LengthUnit{"meter", 1000.0};
  if (n == "inch") return kInch;
  if (n == "feet") return LengthUnit{"feet", 304.8};
  return std::nullopt;
}

}  // namespace probecomp::io
