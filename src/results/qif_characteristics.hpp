#pragma once
// The characteristics part of a QIF 3.0 results document (results/files.hpp, compensated_qif). Private to the
// results layer.

#include <string>

#include "probecomp/inspection/characteristics.hpp"

namespace probecomp::results {

// Adds `inspection`'s characteristics to the QIF document `xml`, which io::contact_points_qif wrote (it has no
// Characteristics yet); lengths in its file unit, `scale` per mm.
void add_characteristics(std::string& xml, const inspection::Inspection& inspection, double scale);

}  // namespace probecomp::results
