// prepare_and_register: the material side of the faces the raw centres alone decide, settled by registering to
// both sides.

#include "probecomp/compensation/pipeline.hpp"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/geometry/statistics.hpp"

#include "warnings.hpp"

namespace probecomp::compensation {

namespace {
// The two sides' robust scales must differ by this factor for the smaller to be believed. Registered to its wrong
// side, a curved face's centres miss the offset surface by what no rigid motion takes up (the offset's curvature
// differs by 2r: the free-form panel of issue 49, 40 µm against 3 µm); a flat face's, or one too gently curved for
// the noise and the part's own deformation to let it show, fit the two sides alike. The part's deformation is in
// both sides' residuals and can even favour the wrong side: measured on the shape suite, the right side's scale
// over the wrong one's 0.53–0.57 (the panel with a 0.15 mm bulge), 0.78 and 0.69 (creased and waved faces), but
// 1.10 (S10, a twisted and dented hood) and 1.44 (D228, a panel with a 0.23 mm crease). Hence 1.6, above the worst
// seen; below kClearSideContrast the choice is stated as weak in the warning, and a sound vote of where the
// centres lie (kSoundVote) decides instead.
constexpr double kSideContrast = 1.6;
constexpr double kClearSideContrast = 2.0;
// The share of a face's raw centres on one side of the nominal that makes that side's vote sound by itself.
constexpr double kSoundVote = 0.9;

using detail::mm;
using detail::um;

// Each face whose side the raw centres decided, once more after registration: the sides were decided or turned
// together, but on a part of several open faces the pose is the large face's, and a small face's centres (touches
// near its edge with the large one) voted before registration as the misalignment put them. Registered, a face on
// its wrong side has its centres a probe diameter inside the material (median signed distance from the nominal
// below −r/2, where r from its probe side): turned, and registered again from the pose found. (A surface of IGES
// example surf128, 1.2° off, no i,j,k: two of its four faces on the wrong side, 298 rows `ok` and 2 mm off.) A lone
// face decides its own pose, so this says nothing of it: the two sides' registrations do.
PreparedRegistration settle_each_face(const cad::Model& model, const geometry::TipRadii& radii, std::span<const Point3> raw,
                                      std::optional<std::span<const Vector3>> approach_normals,
                                      const PrepareOptions& used, const RegisterOptions& options,
                                      PreparedRegistration chosen) {
  const std::vector<cad::MaterialSide>& sides = chosen.prepared.material;
  const auto data_faces = std::count_if(sides.begin(), sides.end(),
                                        [](const cad::MaterialSide& m) { return m.source == cad::MaterialSource::Data; });
  const auto with_points = std::count_if(sides.begin(), sides.end(), [](const cad::MaterialSide& m) { return m.points > 0; });
  if (data_faces == 0 || with_points < 2) return chosen;
  // The offset model's distances plus its radius: each centre's distance from the nominal face, about its tip's
  // radius on the probe side.
  std::vector<std::vector<double>> distance(sides.size());
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const registration::PointMatch& m = chosen.registration.matches[k];
    if (!m.ok() || m.on_edge || !raw[k].allFinite()) continue;
    if (sides[static_cast<std::size_t>(m.face)].source != cad::MaterialSource::Data) continue;
    distance[static_cast<std::size_t>(m.face)].push_back(m.distance + radii.smallest());
  }
  PrepareOptions again = used;
  std::string turned;
  for (std::size_t f = 0; f < sides.size(); ++f) {
    if (distance[f].empty()) continue;
    const double median = geometry::median_in_place(distance[f]);
    if (!(median < -0.5 * radii.smallest())) continue;
    again.flip_faces.push_back(static_cast<int>(f));
    turned += (turned.empty() ? "" : ", ") + std::to_string(model.faces[f].index) + " (median " + mm(median) + " mm)";
  }
  if (turned.empty()) return chosen;
  RegisterOptions from_here = options;
  from_here.icp.initial = chosen.registration.transform;
  PreparedModel p = prepare_model(model, radii, raw, approach_normals, again);
  registration::RegistrationResult r = register_centres(p, raw, from_here);
  r.notes = std::move(chosen.registration.notes);
  r.notes.push_back("face(s) " + turned + " turned to the other side after registration: their centres lay inside the "
                    "material, at that median distance from the nominal");
  return {std::move(p), std::move(r)};
}

}  // namespace

PreparedRegistration prepare_and_register(const cad::Model& model, const geometry::TipRadii& radii,
                                          std::span<const Point3> raw, std::optional<std::span<const Vector3>> approach_normals,
                                          const PrepareOptions& prepare, const RegisterOptions& options) {
  PreparedModel first = prepare_model(model, radii, raw, approach_normals, prepare);
  std::string faces;
  for (std::size_t f = 0; f < first.material.size(); ++f) {
    if (first.material[f].source != cad::MaterialSource::Data) continue;
    faces += (faces.empty() ? "" : ", ") + std::to_string(first.nominal->faces[f].index);
  }
  if (faces.empty()) {
    registration::RegistrationResult r = register_centres(first, raw, options);
    return {std::move(first), std::move(r)};
  }
  // The other hypothesis turns every such face at once: a part's open faces are measured in one pose, so the
  // centres' side of each is wrong or right together, not face by face.
  PrepareOptions other_options = prepare;
  other_options.flip_data_sides = !prepare.flip_data_sides;
  PreparedModel other = prepare_model(model, radii, raw, approach_normals, other_options);
  // Each side's registration, or why it could not be made credible.
  struct Attempt {
    std::optional<registration::RegistrationResult> r;
    std::string error;
  };
  auto attempt = [&](const PreparedModel& p) {
    Attempt a;
    try {
      a.r = register_centres(p, raw, options);
    } catch (const RegistrationError& e) {
      a.error = e.what();
    }
    return a;
  };
  Attempt a = attempt(first), b = attempt(other);
  const std::string which = "the material side of face" + std::string(faces.find(',') != std::string::npos ? "s " : " ") +
                            faces + " (no approach normals, no closed solid)";
  if (!a.r && !b.r) throw RegistrationError(a.error);
  auto keep = [&](PreparedModel& p, registration::RegistrationResult& r, const std::string& why) {
    r.notes.push_back(which + " " + why);
    const PrepareOptions& used = &p == &first ? prepare : other_options;
    return settle_each_face(model, radii, raw, approach_normals, used, options,
                            PreparedRegistration{std::move(p), std::move(r)});
  };
  if (!b.r) return keep(first, *a.r, "was decided from the data: registered to the other side, " + b.error);
  if (!a.r) return keep(other, *b.r, "was decided by registering to both sides: the side the centres first lay on " +
                                         std::string("gave none credible (") + a.error + ")");
  const double sa = a.r->scale, sb = b.r->scale;
  auto figures = [](double keep_scale, double other_scale) {
    return "robust scale of the residuals " + um(keep_scale) + " against " + um(other_scale) + " on the other side" +
           (other_scale < kClearSideContrast * keep_scale
                ? std::string(" (a weak contrast: give each point's approach normal (i,j,k) to be sure)")
                : std::string());
  };
  // Where the centres lie before registration is a test of its own, sound when nearly all of them lie on one side:
  // the pose is then off by less than r where it matters (every centre on the wrong side needs the part moved more
  // than r along the face's normal). It failed on the panel of issue 49, 1–2° off, its centres on both sides. The
  // fit overrules a sound vote only when its contrast is clear (kClearSideContrast).
  double least_share = 1.0;
  for (const cad::MaterialSide& m : first.material) {
    if (m.source == cad::MaterialSource::Data && m.points > 0) {
      least_share = std::min(least_share, static_cast<double>(m.agreeing) / m.points);
    }
  }
  const bool sound_vote = least_share >= kSoundVote;
  const std::string vote = "where the centres lie before registration (" + mm(100.0 * least_share) + " % on one side)";
  if (sb * kClearSideContrast <= sa) {
    return keep(other, *b.r, "was decided by registering to both sides, against the side the centres first lay on: " + figures(sb, sa));
  }
  if (sa * kClearSideContrast <= sb) return keep(first, *a.r, "was decided by registering to both sides: " + figures(sa, sb));
  if (sound_vote) {
    return keep(first, *a.r, "was decided by " + vote + ", the two sides fitting too alike to tell: " + figures(sa, sb));
  }
  if (sb * kSideContrast <= sa) {
    return keep(other, *b.r, "was decided by registering to both sides, against the side the centres first lay on: " + figures(sb, sa));
  }
  if (sa * kSideContrast <= sb) return keep(first, *a.r, "was decided by registering to both sides: " + figures(sa, sb));
  throw RegistrationError("cannot tell " + which + ": registered to either side, the centres fit about as well (robust "
                          "scale of the residuals " + um(sa) + " and " + um(sb) + "), and before registration only " +
                          mm(100.0 * least_share) + " % of them lie on one side. Give each point's approach normal "
                          "(i,j,k) or a CAD model whose faces bound a solid");
}

}  // namespace probecomp::compensation
