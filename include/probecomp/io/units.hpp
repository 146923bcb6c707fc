#pragma once
// Length units of point files (DMIS's UNITS statement and --units): each unit's exact length in mm. Everything
// inside probecomp is in mm; a point file's unit applies to what is read from it and what is written back for it.

#include <optional>
#include <string>
#include <string_view>

namespace probecomp::io {

struct LengthUnit {
  const char* name = "mm";  // as DMIS spells it, in lower case: mm, cm, meter, inch, feet
  double mm = 1.0;          // its length in mm (exact: the inch is 25.4 mm by definition since 1959)
  [[nodiscard]] bool operator==(const LengthUnit& o) const { return mm == o.mm; }
};

inline constexpr LengthUnit kMillimetre{"mm", 1.0};
inline constexpr LengthUnit kInch{"inch", 25.4};

// DMIS's length units by name (mm, cm, meter, inch, feet), case-insensitive; nothing for any other name.
[[nodiscard]] std::optional<LengthUnit> length_unit(std::string_view name);

}  // namespace probecomp::io
