#pragma once
// The compensation's results as point files (DESIGN.md §5): every input row back, in order, as CSV, DMIS or QIF, in
// the input's unit and with its carried columns. Lengths with 9 decimals (nm), unit vectors with 12.

#include <ostream>
#include <string>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/io/point_table.hpp"

namespace probecomp::results {

// x,y,z,nx,ny,nz,deviation,u,face,status, r (each row's tip radius) when the input gave radii, and the input's other
// columns (renamed input_NAME where they clash with ours), lengths in the input's unit. A point that was not
// computed keeps its row: empty fields and the reason in `status`.
[[nodiscard]] std::string compensated_csv(const io::PointTable& input, const compensation::CompensationResult& result);
// The same, written to `out` block by block (the whole text is never held: a million rows are 115 MB); `progress`
// hears the share of rows written after each block.
void write_compensated_csv(std::ostream& out, const io::PointTable& input, const compensation::CompensationResult& result,
                           const io::FileProgress& progress = {});

// One DMIS FA(label) point per computed point (labels from the input's label or id column, else P1, P2, ...),
// with its deviation, face and status in a comment; a comment line for each point not computed. Lengths in the
// input's unit, stated by a UNITS statement first. When the input gave the points their own radii, the tips follow
// it: an SNSDEF per tip and an SNSLCT where the tip changes (io::DmisTips), with the radius each point was
// compensated with.
[[nodiscard]] std::string compensated_dmis(const io::PointTable& input, const compensation::CompensationResult& result,
                                           const std::string& source);

// The results as a QIF 3.0 document (io::contact_points_qif, with each point's status, u and face): one
// MeasuredPointSet per set of the input, with the same id, count and order.
// With an inspection, its characteristics too (DESIGN.md §7): a surface profile characteristic's definition (its
// tolerance and outer disposition), nominal and item under Characteristics, against the standard ISO 1101 added to
// StandardsDefinitions, and its measurement (status PASS, FAIL, INDETERMINATE or NOT_ANALYZED; value with its
// combined standard uncertainty, max and min) under MeasuredCharacteristics; what QIF has no element for (datums,
// points, k, why not evaluated) as probecomp:... attributes. (The document is new: an input QIF's own
// characteristics, like its other sections, are not carried.)
[[nodiscard]] std::string compensated_qif(const io::PointTable& input, const compensation::CompensationResult& result,
                                          const std::string& source, const inspection::Inspection* inspection = nullptr);

}  // namespace probecomp::results
