#pragma once
// The paper's registration Monte Carlo (§5.1, Table 1; DESIGN.md §3): a cube corner of three orthogonal
// 20 mm squares, evenly spread points offset by the probe radius along the outward normal, random
// misalignments, registered by the proposed route (raw centres to the offset model) and the conventional
// one (compensate with the unperturbed model's normals, then register to the nominal).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::studies {

// The corner of the cube [0, size]³ at the origin: faces x = 0, y = 0, z = 0, outward −x, −y, −z, exact
// bilinear plane patches marked as bounding a solid.
[[nodiscard]] cad::Model cube_corner_model(double size = 20.0);

struct RegistrationStudyOptions {
  int trials = 30;
  int points_per_face = 300;     // 900 in all, as in the paper: a 20 × 15 grid of cell centres per face
  double probe_radius = 1.0;     // mm
  double noise = 0.0;            // σ of Gaussian noise on each coordinate of the raw centres, mm
  double max_translation = 1.0;  // misalignment: uniform in ± this on each axis, mm
  double max_rotation = 1.0;     // uniform in ± this about each axis, degrees
  std::uint64_t seed = 1;
  registration::RegistrationOptions registration;  // `initial` is ignored: the nominal pose is the start
};

// Errors in the order rx, ry, rz (degrees), tx, ty, tz (mm): estimated pose minus true misalignment, both
// as geometry::Pose (T = Translation · Rz · Ry · Rx).
using PoseError = std::array<double, 6>;
inline constexpr std::array<const char*, 6> kPoseComponents = {"rx", "ry", "rz", "tx", "ty", "tz"};

struct ErrorStatistics {
  PoseError std{}, mean{};
  // Half-width of the 95 % confidence interval of the mean error, t(0.975, n−1) · std / √n.
  PoseError ci95{};
};

struct RouteOutcome {
  std::vector<PoseError> errors;  // one per trial
  ErrorStatistics stats;
  int converged = 0;
  int max_iterations = 0;         // the most iterations any trial took
};

struct RegistrationStudyResult {
  RouteOutcome proposed, conventional;
  int points = 0;
};

[[nodiscard]] RegistrationStudyResult run_registration_study(const RegistrationStudyOptions& options = {});

// The paper's Table 1, same layout (std, mean, 95 % level), degrees and mm.
struct PaperTable1 {
  ErrorStatistics proposed, conventional;
};
[[nodiscard]] PaperTable1 paper_table1();

[[nodiscard]] ErrorStatistics error_statistics(const std::vector<PoseError>& errors);

}  // namespace probecomp::studies
