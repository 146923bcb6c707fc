#include "probecomp/probe/qualification.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace probecomp::probe {

namespace {

// Gauss–Newton on the sphere stops when a step moves nothing by more than this, mm: far below any CMM's resolution.
constexpr double kStepTolerance = 1e-12;
constexpr int kMaxSteps = 50;
// A fit whose normal matrix (penalty included) has eigenvalues spread wider than this is not taken: the touches
// cannot tell its terms apart.
constexpr double kWorstConditioning = 1e8;
// The support of the model: a direction up to 1.5 gaps from the touches (a gap: the angle from a touch to its
// nearest neighbour, the widest of them), and never less than 10°.
constexpr double kSupportGaps = 1.5;
constexpr double kMinimumSupportDeg = 10.0;
// A higher degree is taken only when it lowers the leave-one-out rms by more than 1 % and by more than 1e-7 mm:
// below that the gain is round-off (noise-free touches) or one noise traded for another.
constexpr double kLeaveOneOutGain = 0.99;
constexpr double kLeaveOneOutResolution = 1e-7;
// The roughness penalty λ = n·10^s, s from 2 (all but flat) down to −4 in half decades. Over a cap (a sphere is
// touched from above) harmonics of even and odd degree are nearly alike, so an unpenalised model of degree 5 varies
// 44 times the noise at the pole; the penalty keeps the smoothest of the near-equal fits. Below 10^−4 a model of
// degree 6 from 120 touches at 0.3 µm had errors of 0.9 µm where 10^−4 leaves 0.5 µm, and noise-free touches gain
// nothing there (tests/probe/qualification_test.cpp).
constexpr double kLogLambdaHigh = 2.0, kLogLambdaLow = -4.0, kLogLambdaStep = 0.5;

double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

double angle_between(const Vector3& a, const Vector3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// The algebraic sphere through the centres (|c|² = 2 c·C + k, linear): a start for the geometric fit.
Point3 algebraic_centre(std::span<const Point3> c) {
  Eigen::MatrixXd a(c.size(), 4);
  Eigen::VectorXd b(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    a.row(static_cast<Eigen::Index>(i)) << 2.0 * c[i].x(), 2.0 * c[i].y(), 2.0 * c[i].z(), 1.0;
    b(static_cast<Eigen::Index>(i)) = c[i].squaredNorm();
  }
  const Eigen::Vector4d x = a.colPivHouseholderQr().solve(b);
  return x.head<3>();
}

// The fit of |c_i − C| − R = Σ a_k Y_k(d_i) by Gauss–Newton in x = (C, a), penalised by λ Σ w_k a_k²: `basis` is
// n × K (fixed: the travel directions do not move with C), `penalty` the weights w_k. Residuals, the Jacobian at the
// solution and the parameters.
struct SphereFit {
  bool converged = false;
  Point3 centre = Point3::Zero();
  Eigen::VectorXd coefficients{};
  Eigen::VectorXd residuals{};
  Eigen::MatrixXd jacobian{};
  Eigen::VectorXd penalty{};  // λ w over x (0 for the centre)
};

void evaluate(std::span<const Point3> c, double sphere_radius, const Eigen::MatrixXd& basis, SphereFit& f) {
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(c.size()); ++i) {
    const Vector3 out = c[static_cast<std::size_t>(i)] - f.centre;
    const double distance = out.norm();
    f.residuals(i) = distance - sphere_radius - basis.row(i).dot(f.coefficients);
    f.jacobian.block<1, 3>(i, 0) = -out.transpose() / distance;
    f.jacobian.block(i, 3, 1, basis.cols()) = -basis.row(i);
  }
}

SphereFit fit_sphere(std::span<const Point3> c, double sphere_radius, const Eigen::MatrixXd& basis,
                     const Eigen::VectorXd& penalty, Point3 centre, Eigen::VectorXd coefficients) {
  const auto n = static_cast<Eigen::Index>(c.size()), k = basis.cols();
  SphereFit f;
  f.centre = centre;
  f.coefficients = std::move(coefficients);
  f.jacobian.resize(n, 3 + k);
  f.residuals.resize(n);
  f.penalty = Eigen::VectorXd::Zero(3 + k);
  f.penalty.tail(k) = penalty;
  for (int step = 0; step < kMaxSteps; ++step) {
    evaluate(c, sphere_radius, basis, f);
    Eigen::VectorXd x(3 + k);
    x << f.centre, f.coefficients;
    const Eigen::MatrixXd normal = f.jacobian.transpose() * f.jacobian + Eigen::MatrixXd(f.penalty.asDiagonal());
    const Eigen::VectorXd dx =
        normal.ldlt().solve(-(f.jacobian.transpose() * f.residuals + f.penalty.cwiseProduct(x)));
    if (!dx.allFinite()) return f;
    f.centre += dx.head<3>();
    f.coefficients += dx.tail(k);
    if (dx.cwiseAbs().maxCoeff() < kStepTolerance) {
      evaluate(c, sphere_radius, basis, f);
      f.converged = true;
      break;
    }
  }
  return f;
}

Eigen::MatrixXd harmonic_basis(std::span<const Vector3> travel, const std::vector<HarmonicIndex>& terms) {
  Eigen::MatrixXd b(static_cast<Eigen::Index>(travel.size()), static_cast<Eigen::Index>(terms.size()));
  for (std::size_t i = 0; i < travel.size(); ++i) {
    const std::vector<double> y = real_harmonics(travel[i], terms);
    for (std::size_t k = 0; k < y.size(); ++k) b(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = y[k];
  }
  return b;
}

// The roughness of each term: its share of the surface Laplacian's energy, (l(l+1))², over degree 2's (36), so
// that degree 0 is free and λ weighs degree 2 as one unit.
Eigen::VectorXd roughness(const std::vector<HarmonicIndex>& terms) {
  Eigen::VectorXd w(static_cast<Eigen::Index>(terms.size()));
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const double l = terms[k].l;
    w(static_cast<Eigen::Index>(k)) = std::pow(l * (l + 1.0), 2) / 36.0;
  }
  return w;
}

// Leave-one-out rms of the linearised penalised fit, e_i / (1 − h_ii) with H = J A⁻¹ Jᵀ, A = JᵀJ + Λ; and the
// parameters' covariance σ² A⁻¹ JᵀJ A⁻¹, σ² = |e|² / (n − tr H). Infinite when A is too ill-conditioned or a
// touch has all the weight of a term.
struct Assessed {
  double loo_rms = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd covariance{};  // of (C, a), mm²
};

Assessed assess(const SphereFit& f) {
  Assessed out;
  const Eigen::MatrixXd jtj = f.jacobian.transpose() * f.jacobian;
  const Eigen::MatrixXd a = jtj + Eigen::MatrixXd(f.penalty.asDiagonal());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
  const Eigen::VectorXd values = eigen.eigenvalues();
  if (!(values(0) > 0.0) || values(values.size() - 1) / values(0) > kWorstConditioning) return out;
  const Eigen::MatrixXd a_inverse = eigen.eigenvectors() * values.cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  const auto n = f.jacobian.rows();
  double sum = 0.0, trace = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double h = f.jacobian.row(i) * a_inverse * f.jacobian.row(i).transpose();
    if (h > 1.0 - 1e-9) return out;
    trace += h;
    sum += std::pow(f.residuals(i) / (1.0 - h), 2);
  }
  out.loo_rms = std::sqrt(sum / static_cast<double>(n));
  const double variance = f.residuals.squaredNorm() / std::max(static_cast<double>(n) - trace, 1.0);
  out.covariance = variance * a_inverse * jtj * a_inverse;
  return out;
}

}  // namespace

const char* to_string(QualificationStatus s) {
  switch (s) {
    case QualificationStatus::OK: return "ok";
    case QualificationStatus::TooFewTouches: return "too-few-touches";
    case QualificationStatus::NumericalError: return "numerical-error";
  }
  return "?";
}

int RadiusModel::degree() const {
  int d = 0;
  for (const HarmonicIndex& t : terms) d = std::max(d, t.l);
  return d;
}

double RadiusModel::radius(const Vector3& travel) const {
  const std::vector<double> y = real_harmonics(travel, terms);
  double r = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) r += coefficients[k] * y[k];
  return r;
}

double RadiusModel::uncertainty(const Vector3& travel) const {
  const std::vector<double> y = real_harmonics(travel, terms);
  double v = 0.0;
  for (std::size_t a = 0; a < y.size(); ++a) {
    for (std::size_t b = 0; b < y.size(); ++b) v += y[a] * covariance[a][b] * y[b];
  }
  return std::sqrt(std::max(v, 0.0));
}

double RadiusModel::variation() const {
  double sum = 0.0;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    if (terms[k].l > 0) sum += coefficients[k] * coefficients[k];
  }
  return std::sqrt(sum);
}

StylusQualification qualify_stylus(std::string stylus, std::span<const Point3> centres,
                                   std::span<const Vector3> normals, double sphere_diameter,
                                   const QualificationOptions& options) {
  StylusQualification q;
  q.stylus = std::move(stylus);
  q.touches = static_cast<int>(centres.size());
  q.sphere_diameter = sphere_diameter;
  if (q.touches < kMinimumTouches) {
    q.reason = std::to_string(q.touches) + " touches; a sphere needs at least " + std::to_string(kMinimumTouches);
    return q;
  }
  const double sphere_radius = sphere_diameter / 2.0;
  const auto n = static_cast<Eigen::Index>(centres.size());

  // The plain sphere: centre and one radius.
  const Eigen::MatrixXd constant = Eigen::MatrixXd::Ones(n, 1);
  Point3 start = algebraic_centre(centres);
  double mean_distance = 0.0;
  for (const Point3& c : centres) mean_distance += (c - start).norm() / static_cast<double>(n);
  const SphereFit plain = fit_sphere(centres, sphere_radius, constant, Eigen::VectorXd::Zero(1), start,
                                     Eigen::VectorXd::Constant(1, mean_distance - sphere_radius));
  const Assessed plain_assessed = assess(plain);
  if (!plain.converged || !plain_assessed.covariance.allFinite() || plain_assessed.covariance.size() == 0) {
    q.status = QualificationStatus::NumericalError;
    q.reason = "the sphere fit did not converge (are the touches on one sphere, from several directions?)";
    return q;
  }
  q.sphere_centre = plain.centre;
  q.effective_radius = plain.coefficients(0);
  q.effective_radius_u = std::sqrt(plain_assessed.covariance(3, 3));
  q.sphere_rms = std::sqrt(plain.residuals.squaredNorm() / static_cast<double>(n));
  q.form_error = plain.residuals.maxCoeff() - plain.residuals.minCoeff();

  // Travel directions: against the programmed outward normal, else towards the fitted centre.
  q.directions.reserve(centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) {
    q.directions.push_back(normals.empty() ? Vector3((plain.centre - centres[i]).normalized())
                                           : Vector3(-normals[i].normalized()));
  }

  // The degree of the model: the lowest leave-one-out rms among those the touches can carry.
  const int n_touches = q.touches;
  SphereFit best = plain;
  Assessed best_assessed = plain_assessed;
  std::vector<HarmonicIndex> best_terms = harmonic_terms(0, true);
  double best_log_lambda = 0.0;
  for (int degree = 2; degree <= options.max_degree; ++degree) {
    const std::vector<HarmonicIndex> terms = harmonic_terms(degree, true);
    const int parameters = 3 + static_cast<int>(terms.size());
    if (n_touches < options.touches_per_parameter * parameters) break;
    const Eigen::MatrixXd basis = harmonic_basis(q.directions, terms);
    const Eigen::VectorXd w = roughness(terms);
    // From the smoothest down, so that a rougher model must earn its place (kLeaveOneOutGain).
    for (double log_lambda = kLogLambdaHigh; log_lambda >= kLogLambdaLow - 1e-9; log_lambda -= kLogLambdaStep) {
      Eigen::VectorXd a0 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(terms.size()));
      a0(0) = q.effective_radius;
      const double lambda = static_cast<double>(n_touches) * std::pow(10.0, log_lambda);
      const SphereFit f = fit_sphere(centres, sphere_radius, basis, lambda * w, plain.centre, a0);
      if (!f.converged) continue;
      const Assessed a = assess(f);
      if (a.loo_rms < kLeaveOneOutGain * best_assessed.loo_rms &&
          a.loo_rms < best_assessed.loo_rms - kLeaveOneOutResolution) {
        best = f;
        best_assessed = a;
        best_terms = terms;
        best_log_lambda = log_lambda;
      }
    }
  }
  q.model.terms = best_terms;
  q.model.coefficients.assign(best.coefficients.data(), best.coefficients.data() + best.coefficients.size());
  const auto k = static_cast<Eigen::Index>(best_terms.size());
  q.model.covariance.assign(best_terms.size(), std::vector<double>(best_terms.size(), 0.0));
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) {
      q.model.covariance[static_cast<std::size_t>(a)][static_cast<std::size_t>(b)] = best_assessed.covariance(3 + a, 3 + b);
    }
  }
  q.residual = std::sqrt(best.residuals.squaredNorm() / static_cast<double>(n));
  q.loo_residual = best_assessed.loo_rms;
  q.model.log10_smoothing = best_terms.size() > 1 ? best_log_lambda : 0.0;

  double widest_gap = 0.0;
  for (std::size_t i = 0; i < q.directions.size(); ++i) {
    double nearest = std::numbers::pi;
    for (std::size_t j = 0; j < q.directions.size(); ++j) {
      if (j != i) nearest = std::min(nearest, angle_between(q.directions[i], q.directions[j]));
    }
    widest_gap = std::max(widest_gap, nearest);
  }
  q.support_angle_deg = std::max(kMinimumSupportDeg, kSupportGaps * degrees(widest_gap));
  q.status = QualificationStatus::OK;
  return q;
}

EffectiveRadius effective_radius(const StylusQualification& q, const Vector3& travel) {
  double nearest = std::numbers::pi;
  for (const Vector3& d : q.directions) nearest = std::min(nearest, angle_between(travel, d));
  if (degrees(nearest) > q.support_angle_deg) {
    return {q.effective_radius, std::hypot(q.effective_radius_u, q.model.variation()), true};
  }
  return {q.model.radius(travel), q.model.uncertainty(travel), false};
}

std::vector<double> Qualification::effective_radii() const {
  std::vector<double> out;
  for (const StylusQualification& s : styli) {
    if (s.status == QualificationStatus::OK) out.push_back(s.effective_radius);
  }
  return out;
}

const StylusQualification* Qualification::find(const std::string& stylus) const {
  for (const StylusQualification& s : styli) {
    if (s.stylus == stylus) return &s;
  }
  return nullptr;
}

}  // namespace probecomp::probe
