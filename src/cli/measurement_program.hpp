#pragma once
// A DMIS part program of single points (DMIS 5.3): each a nominal feature F(label), measured by one PTMEAS at it along
// its outward normal (the approach direction, as our DMIS reader takes i, j, k). `plan` writes one; `compensate
// --replan` writes one of the points to measure again.

#include <string>
#include <vector>

#include "probecomp/geometry/types.hpp"

namespace probecomp::cli {

struct ProgrammedTouch {
  std::string label;
  Point3 point = Point3::Zero();    // mm, the frame the machine measures in
  Vector3 normal = Vector3::UnitZ();  // outward unit normal
};

// The program: DMISMN with `title`, UNITS/MM, then F/MEAS/PTMEAS/ENDMES per touch, `comments` as $$ lines after the
// header, and ENDFIL.
[[nodiscard]] std::string dmis_measurement_program(const std::string& title, const std::vector<ProgrammedTouch>& touches,
                                                   const std::vector<std::string>& comments = {});

}  // namespace probecomp::cli
