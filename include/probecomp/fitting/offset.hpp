#pragma once
// Offset surface S + d·n as a NURBS (DESIGN.md §2 step 2: the probe-centre surface is the part surface offset
// by the tip radius). Same degrees and parametrisation as S, so a trimmed face keeps its trim: samples of the
// true offset at about 3 parameters per knot span are fitted by least squares with S's knots and weights;
// the fit is checked against the true offset on a denser grid, and the spans that miss the tolerance are cut
// (knots inserted into S's knot vectors, shape unchanged) into as many pieces as the fit's order h^(p+1) says
// they need, until it holds or the rounds run out.

#include <functional>

#include "probecomp/nurbs/surface.hpp"

namespace probecomp::fitting {

struct OffsetOptions {
  double tolerance = 1e-4;  // mm: largest allowed |fit(u,v) − (S + d·n)(u,v)| on the check grid
  int samples_per_span = 3;  // fitted samples per knot span and direction
  // Check parameters per knot span and direction, between the samples. Eight resolves a span's error curve
  // (a few oscillations of the fit about the offset) to a few per cent of its peak.
  int checks_per_span = 8;
  int max_rounds = 8;        // fits; each but the first follows a knot insertion
};

struct OffsetResult {
  enum class Status {
    OK,                   // within the tolerance
    ToleranceNotReached,  // `deviation` is the best reached in max_rounds
    FoldsOver,            // S curves towards the offset side more tightly than |d|: the offset folds over
    Degenerate,           // S has no normal somewhere (e.g. a collapsed edge it cannot be continued across)
  };
  Status status = Status::Degenerate;
  nurbs::Surface surface;     // the offset (the last fit, for every status but Degenerate)
  double deviation = 0.0;     // largest |fit − true offset| on the check grid, mm
  int rounds = 0;             // fits made
  int knots_inserted = 0;     // knots added to S's u and v knot vectors together
  // The smallest radius of curvature of S on the side the offset goes (infinite where S is flat or curves
  // away), and where it was found: the offset folds when it is below |d|.
  double min_radius_towards_offset = 0.0;
  double at_u = 0.0, at_v = 0.0;

  [[nodiscard]] bool ok() const { return status == Status::OK; }
};

// Offset along the unit normal n = S_u × S_v / |S_u × S_v| (d < 0: the other side).
[[nodiscard]] OffsetResult offset_surface(const nurbs::Surface& s, double d, const OffsetOptions& options = {});

// S + d(S)·n: a distance that varies with the point of S (a shape deviation along the normal, as the simulator
// makes). The same fit and refinement; not checked for folding over (the caller's d may legitimately exceed a
// radius of S somewhere it is small), and the tolerance measures the gap along n, exact only where ∇d is small.
using OffsetDistance = std::function<double(const Point3&)>;
[[nodiscard]] OffsetResult displaced_surface(const nurbs::Surface& s, const OffsetDistance& d,
                                             const OffsetOptions& options = {});

[[nodiscard]] const char* to_string(OffsetResult::Status s);

}  // namespace probecomp::fitting
