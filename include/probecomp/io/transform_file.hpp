#pragma once
// A rigid transform as a file (--initial-transform): a 4 × 4 homogeneous matrix, CAD → machine (the convention
// of --json's "transform"), four lines of four numbers separated by spaces, tabs or commas; blank lines and lines
// starting with '#' are skipped. Its translation is in mm.

#include <filesystem>

#include "probecomp/geometry/rigid.hpp"

namespace probecomp::io {

// Throws InputError ("FILE:LINE: cause") for a missing file, a line without four numbers, more or fewer than four
// rows, a last row other than 0 0 0 1, or an upper-left 3 × 3 that is not a rotation (orthonormal to 1e-6,
// determinant +1: no scaling, shear or mirroring).
[[nodiscard]] geometry::RigidTransform read_transform(const std::filesystem::path& path);

}  // namespace probecomp::io
