#pragma once
// Measured points in DMIS (DESIGN.md §5): `F(label) = FEAT/POINT,CART,x,y,z,i,j,k` (nominal or programmed) and
// `FA(label) = FEAT/POINT,CART,x,y,z,i,j,k` (actual, as measured), with `$` at the end of a line continuing the
// statement and `$$` starting a comment. `UNITS/MM|CM|METER|INCH|FEET,...` sets the length unit of the points after
// it (MM until one does). Tips: `S(name)=SNSDEF/PROBE,INDEX|FIXED,POL,tilt,rotate,i,j,k,length,diameter` or
// `...,CART,x,y,z,i,j,k,diameter` defines a ball tip (SA(name) likewise: a calibrated one), in the unit in force;
// `SNSLCT/S(name)` selects it for the points after it. Other statements are skipped.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/io/point_table.hpp"

namespace probecomp::io {

// The measured points of a .dmo file: the FA(...) points when the file has any, else its F(...) points (a file of
// measured points written as features). The table's columns are label, x, y, z and i, j, k when every point has
// them, and r and tip when a sensor was selected before any point (a point before the first selection has an
// empty r and tip); `label` and `tip` are carried to outputs, and each used sensor's definition is kept
// (PointTable::sensor_definitions). The table's unit is the one in force at its first point (a point read in
// another has its row written in this one); `declared`, when given, is the unit the user says the file is in
// (--units): a UNITS statement that disagrees is an error, and a file without one is read in it. Throws
// InputError ("FILE:LINE: cause") for a malformed point or UNITS statement, a non-finite or zero normal, points
// with and without normals mixed, a ball diameter that is not a positive number, a selection of a sensor no
// SNSDEF before it defines or whose definition is not one of the forms above (a DISC tip, a VEC form, ...), or no
// points.
[[nodiscard]] PointTable read_point_dmis(const std::filesystem::path& path,
                                         std::optional<LengthUnit> declared = std::nullopt);

// .dmo, .dmi or .dms, in any case.
[[nodiscard]] bool is_dmis(const std::filesystem::path& path);

// One `FA(label)=FEAT/POINT,CART,x,y,z,i,j,k` statement: x in mm written in `unit` (9 decimals), the unit normal
// with 12.
[[nodiscard]] std::string dmis_point(const std::string& label, const Point3& x, const Vector3& n,
                                     LengthUnit unit = kMillimetre);

// The `UNITS/...,ANGDEC` statement of a length unit.
[[nodiscard]] std::string dmis_units(LengthUnit unit);

// The DMIS label of row k: the table's label or id column, else P1, P2, ...
[[nodiscard]] std::string dmis_label(const PointTable& table, std::size_t k);

// The sensors of a DMIS output. Each row's tip is named by the table's `tip` column, else TIP1, TIP2, ... by
// distinct radius (a name met with two radii gets a suffix); each is defined once, by the input's own SNSDEF when
// it has one with that diameter, else by a neutral `INDEX,POL,0,0,0,0,1,0` orientation with the real diameter
// (said in a `$$` comment), and selected before each point whose tip differs from the previous point's.
class DmisTips {
 public:
  // `radii`: each row's tip radius in the table's unit. Throws InputError for a row without one (NaN) after a row
  // with one: DMIS has no way to deselect a sensor.
  DmisTips(const PointTable& table, const std::vector<double>& radii);
  // The S(name)=SNSDEF/... statements, every tip's, for the start of the file.
  [[nodiscard]] std::string definitions() const;
  // "SNSLCT/S(name)\n" before row k when its tip differs from the row last selected for, else "".
  [[nodiscard]] std::string select(std::size_t k);

 private:
  struct Tip {
    std::string name, definition;  // definition: after `S(name)=`; empty: the neutral one
    double radius = 0.0;
  };
  std::vector<Tip> tips_;
  std::vector<int> tip_of_row_;  // index into tips_, -1: none
  int selected_ = -1;
};

// The table as DMIS (probecomp convert): a `$$` header naming `source`, the UNITS statement, the sensors
// (DmisTips) when the table has radii, and one FA(label)=FEAT/POINT,CART,x,y,z[,i,j,k] per row, each number the
// shortest text that reads back as the row's value in the table's unit.
[[nodiscard]] std::string points_dmis(const PointTable& table, const std::string& source);

}  // namespace probecomp::io
