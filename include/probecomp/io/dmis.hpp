#pragma once
// Measured points in DMIS (DESIGN.md §5): `F(label) = FEAT/POINT,CART,x,y,z,i,j,k` (nominal or programmed) and
// `FA(label) = FEAT/POINT,CART,x,y,z,i,j,k` (actual, as measured), with `$` at the end of a line continuing the
// statement and `$$` starting a comment. Other statements are skipped.

#include <filesystem>
#include <string>

#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// The measured points of a .dmo file: the FA(...) points when the file has any, else its F(...) points (a file of
// measured points written as features). The table's columns are label, x, y, z and i, j, k when every point has
// them; `label` is carried to outputs. Throws InputError ("FILE:LINE: cause") for a malformed point statement, a
// non-finite or zero normal, points with and without normals mixed, or no points.
[[nodiscard]] PointTable read_point_dmis(const std::filesystem::path& path);

// By extension: .dmo/.dmi/.dms (DMIS) or anything else as CSV.
[[nodiscard]] PointTable read_points(const std::filesystem::path& path);
[[nodiscard]] bool is_dmis(const std::filesystem::path& path);

// One `FA(label)=FEAT/POINT,CART,x,y,z,i,j,k` statement (12 decimals for lengths, mm; 12 for the unit normal).
[[nodiscard]] std::string dmis_point(const std::string& label, const Point3& x, const Vector3& n);

}  // namespace probecomp::io
