#pragma once
// A clamped (open) knot vector U = {u_0, ..., u_m} for degree p, validated on construction
// (The NURBS Book, eq. 2.13): non-decreasing, first and last knots of multiplicity p+1, interior
// multiplicities at most p, a domain of positive length.

#include <span>
#include <stdexcept>
#include <vector>

#include "probecomp/error.hpp"

namespace probecomp::nurbs {

// Highest degree the kernel evaluates; stack buffers are sized for it. CAD systems rarely exceed 9;
// OpenCASCADE allows 25, and the CAD reader reports anything above this bound as unsupported.
inline constexpr int kMaxDegree = 15;

// Thrown for knot vectors, control nets and parameters that break the kernel's preconditions (an InputError:
// geometry handed in that the kernel cannot use).
class InvalidGeometry : public InputError {
 public:
  using InputError::InputError;
};

class KnotVector {
 public:
  KnotVector() = default;
  // Throws InvalidGeometry with the reason when the knots are not a valid clamped vector for degree p.
  KnotVector(std::vector<double> knots, int p);

  // Clamped uniform knot vector on [a, b] with `spans` equal spans.
  [[nodiscard]] static KnotVector uniform(int p, int spans, double a = 0.0, double b = 1.0);

  [[nodiscard]] int degree() const { return p_; }
  [[nodiscard]] std::span<const double> knots() const { return U_; }
  [[nodiscard]] double operator[](int i) const { return U_[static_cast<std::size_t>(i)]; }
  [[nodiscard]] int size() const { return static_cast<int>(U_.size()); }
  // Number of basis functions n+1 = m - p.
  [[nodiscard]] int num_basis() const { return size() - p_ - 1; }
  [[nodiscard]] double front() const { return U_[static_cast<std::size_t>(p_)]; }
  [[nodiscard]] double back() const { return U_[U_.size() - 1 - static_cast<std::size_t>(p_)]; }

  // A2.1: the span index i with u_i <= u < u_{i+1}; u = back() maps to the last non-empty span.
  // u outside the domain is clamped to it.
  [[nodiscard]] int find_span(double u) const;
  // How many times u occurs in U (0 if it is not a knot).
  [[nodiscard]] int multiplicity(double u) const;
  // The distinct knots, front() to back(), in order: the breakpoints of the spans.
  [[nodiscard]] std::vector<double> breakpoints() const;
  [[nodiscard]] int num_spans() const { return static_cast<int>(breakpoints().size()) - 1; }
  // Greville abscissa of basis function i, the average of its p interior knots (The NURBS Book, eq. 9.24): where
  // control point i acts most; control points there reproduce a linear function exactly.
  [[nodiscard]] double greville(int i) const;

 private:
  std::vector<double> U_;
  int p_ = 0;
};

}  // namespace probecomp::nurbs
