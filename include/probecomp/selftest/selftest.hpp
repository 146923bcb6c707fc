#pragma once
// Known-answer checks a user runs on their own machine (`probecomp selftest`), in the spirit of ISO 10360-6 and
// NIST's algorithm testing: each computes something whose exact answer is known without the code under test
// (a closed form, a reference data set, stored truth) and compares. Together they cover the product's chain:
// closest points and offsets on exact NURBS of a plane, sphere, cylinder and torus; a fit through exact data;
// the registration of a known motion; the conventional and CAD-based compensation of a stored free-form
// measurement against its stored true contact points; and least-squares planes, spheres and cylinders on
// NIST-style reference data (reference_elements.hpp).

#include <functional>
#include <string>
#include <vector>

namespace probecomp::selftest {

struct Check {
  std::string name;
  double error = 0.0;  // measured, in `unit`; infinite when the computation failed
  double limit = 0.0;  // the check passes when error ≤ limit
  std::string unit;    // "mm", or "%" for a share of points
  std::string detail;  // what failed, when it did

  [[nodiscard]] bool passed() const { return error <= limit; }
};

// Runs every check in a fixed order, calling `done` as each finishes. Deterministic.
[[nodiscard]] std::vector<Check> run_selftest(const std::function<void(const Check&)>& done = {});

}  // namespace probecomp::selftest
