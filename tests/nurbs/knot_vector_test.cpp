#include "probecomp/nurbs/knot_vector.hpp"

#include <gtest/gtest.h>

#include <random>

namespace probecomp::nurbs {
namespace {

void expect_invalid(std::vector<double> U, int p, const std::string& fragment) {
  try {
    KnotVector kv(std::move(U), p);
    FAIL() << "accepted an invalid knot vector (expected: " << fragment << ")";
  } catch (const InvalidGeometry& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(KnotVector, RejectsInvalidVectorsWithTheReason) {
  expect_invalid({0, 0, 0, 1, 1}, 2, "too few");
  expect_invalid({0, 0, 0, 0.6, 0.4, 1, 1, 1}, 2, "decrease");
  expect_invalid({0, 0, 0.1, 0.5, 1, 1, 1}, 2, "clamped");
  expect_invalid({0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1}, 2, "multiplicity 3");
  expect_invalid({0, 0, 0, 0, 1, 1, 1}, 2, "above p+1");
  expect_invalid({1, 1, 1, 1, 1, 1}, 2, "empty");
  expect_invalid({0, 0, 0, std::nan(""), 1, 1, 1}, 2, "not finite");
  expect_invalid({0, 1}, 0, "degree");
}

TEST(KnotVector, AcceptsClampedVectorsAndReportsTheirShape) {
  const KnotVector U({0, 0, 0, 0.25, 0.5, 0.5, 1, 1, 1}, 2);
  EXPECT_EQ(U.degree(), 2);
  EXPECT_EQ(U.num_basis(), 6);
  EXPECT_DOUBLE_EQ(U.front(), 0.0);
  EXPECT_DOUBLE_EQ(U.back(), 1.0);
  EXPECT_EQ(U.multiplicity(0.5), 2);
  EXPECT_EQ(U.multiplicity(0.3), 0);
  EXPECT_EQ(U.breakpoints(), (std::vector<double>{0, 0.25, 0.5, 1}));
  EXPECT_EQ(U.num_spans(), 3);
}

TEST(KnotVector, FindSpanAgreesWithLinearSearch) {
  const KnotVector U({-2, -2, -2, -2, -1, 0.5, 0.5, 3, 4, 4, 4, 4}, 3);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> dist(-2.0, 4.0);
  for (int t = 0; t < 2000; ++t) {
    const double u = t < 6 ? std::vector<double>{-2, -1, 0.5, 3, 4, 4}[t] : dist(rng);
    const int span = U.find_span(u);
    if (u == U.back()) {
      EXPECT_EQ(span, U.num_basis() - 1);  // last non-empty span
      continue;
    }
    EXPECT_LE(U[span], u);
    EXPECT_LT(u, U[span + 1]);
    EXPECT_GE(span, U.degree());
    EXPECT_LE(span, U.num_basis() - 1);
  }
  EXPECT_EQ(U.find_span(-5.0), U.degree());       // clamped below
  EXPECT_EQ(U.find_span(9.0), U.num_basis() - 1);  // clamped above
}

TEST(KnotVector, UniformHasEqualSpans) {
  const KnotVector U = KnotVector::uniform(3, 4, 0.0, 2.0);
  EXPECT_EQ(U.knots().size(), 4u + 1 + 2 * 3);
  EXPECT_EQ(U.breakpoints(), (std::vector<double>{0, 0.5, 1.0, 1.5, 2.0}));
}

}  // namespace
}  // namespace probecomp::nurbs
