#pragma once
// Measured points in DMIS (DESIGN.md §5): `F(label) = FEAT/POINT,CART,x,y,z,i,j,k` (nominal or programmed) and
// `FA(label) = FEAT/POINT,CART,x,y,z,i,j,k` (actual, as measured), with `$` at the end of a line continuing the
// statement and `$$` starting a comment. `UNITS/MM|CM|METER|INCH|FEET,...` sets the length unit of the points after
// it (MM until one does). Other statements are skipped.

#include <filesystem>
#include <optional>
#include <string>

#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// The measured points of a .dmo file: the FA(...) points when the file has any, else its F(...) points (a file of
// measured points written as features). The table's columns are label, x, y, z and i, j, k when every point has
// them; `label` is carried to outputs. The table's unit is the one in force at its first point; `declared`, when
// given, is the unit the user says the file is in (--units): a UNITS statement that disagrees is an error, and a
// file without one is read in it. Throws InputError ("FILE:LINE: cause") for a malformed point or UNITS statement,
// a non-finite or zero normal, points with and without normals mixed, or no points.
[[nodiscard]] PointTable read_point_dmis(const std::filesystem::path& path,
                                         std::optional<LengthUnit> declared = std::nullopt);

// By extension: .dmo/.dmi/.dms (DMIS) or anything else as CSV (in `declared`, default mm).
[[nodiscard]] PointTable read_points(const std::filesystem::path& path,
                                     std::optional<LengthUnit> declared = std::nullopt);
[[nodiscard]] bool is_dmis(const std::filesystem::path& path);

// One `FA(label)=FEAT/POINT,CART,x,y,z,i,j,k` statement: x in mm written in `unit` (9 decimals), the unit normal
// with 12.
[[nodiscard]] std::string dmis_point(const std::string& label, const Point3& x, const Vector3& n,
                                     LengthUnit unit = kMillimetre);

// The `UNITS/...,ANGDEC` statement of a length unit.
[[nodiscard]] std::string dmis_units(LengthUnit unit);

}  // namespace probecomp::io
