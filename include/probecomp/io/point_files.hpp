#pragma once
// Point files by name: the one place that maps a path to its format (CSV, DMIS or QIF) and reads or writes a point
// table in it, for every command, the Python package and the results' writers.

#include <filesystem>
#include <optional>
#include <string>

#include "probecomp/io/point_table.hpp"
#include "probecomp/io/units.hpp"

namespace probecomp::io {

enum class PointFormat { Csv, Dmis, Qif };

// By extension, in any case: .dmo/.dmi/.dms DMIS, .qif QIF, anything else CSV (a CSV may have any name).
[[nodiscard]] PointFormat point_format(const std::filesystem::path& path);
// As point_format, but only for the extensions a writer names its files by (.csv, .dmo/.dmi/.dms, .qif): none for
// any other, which the caller refuses with its own words.
[[nodiscard]] std::optional<PointFormat> written_point_format(const std::filesystem::path& path);

// The probe centres of a point file in its format (io/point_table.hpp, io/dmis.hpp, io/qif.hpp for each one's
// columns and errors). `progress` is heard while a CSV is read (the usual form of a long scan).
[[nodiscard]] PointTable read_points(const std::filesystem::path& path,
                                     std::optional<LengthUnit> declared = std::nullopt,
                                     const FileProgress& progress = {}, NumberText number_text = NumberText::Keep);

// The table as a point file of that format, every number the shortest text that reads back as the row's value;
// `source` is named in a DMIS file's header.
[[nodiscard]] std::string points_text(const PointTable& table, PointFormat format, const std::string& source);

}  // namespace probecomp::io
