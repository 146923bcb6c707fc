#pragma once
// Parsers for the command line's small languages. Each throws std::invalid_argument with a one-line message
// that names the option and shows the expected form.

#include <string>
#include <vector>

#include "probecomp/geometry/rigid.hpp"
#include "probecomp/io/format.hpp"
#include "probecomp/simulation/deformation.hpp"
#include "probecomp/simulation/pretravel.hpp"

namespace probecomp::cli {

// The commands format numbers as the result files do.
using io::fmt;
using io::mm;
using io::unit;

// --probe-radius: a positive, finite number of mm.
void check_probe_radius(double r);

// "0,3,5-9" → {0, 3, 5, 6, 7, 8, 9} (--faces).
[[nodiscard]] std::vector<int> parse_face_list(const std::string& list);

// "tx,ty,tz,rx,ry,rz" (mm, degrees; T = Translation · Rz · Ry · Rx) → the placement CAD → machine (--misalign).
[[nodiscard]] geometry::RigidTransform parse_misalignment(const std::string& spec);

// Adds one --deform specification to `d`:
//   bump:X,Y,Z,A,W              Gaussian bump at (X,Y,Z), amplitude A (mm, < 0 a dent), width W (its σ, mm)
//   sine:A,L,DX,DY,DZ[,OX,OY,OZ[,W[,PHASE]]]
//                               A·sin(2π d·(x − o)/L + PHASE°) along direction d, origin o (default 0,0,0),
//                               under a Gaussian window of σ W about o when W > 0
void add_deformation(const std::string& spec, simulation::Deformation& d);

// "P0,B,A[,N[,PHASE]]" (mm, mm, mm, lobe count, degrees) → the simulated probe's pre-travel (--pretravel), the
// stylus pointing down (−z): p(d) = P0 + B·cos²θ + A·sin²θ·cos(N(φ − PHASE)), N 3 and PHASE 0 by default.
[[nodiscard]] simulation::Pretravel parse_pretravel(const std::string& spec);

}  // namespace probecomp::cli
