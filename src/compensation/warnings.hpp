#pragma once
// The run's warnings (CompensationResult::warnings: what the user must know to read the result right, one line
// each), and the lengths written in them and in error messages. Private to compensation/.

#include <span>
#include <string>
#include <vector>

#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/geometry/tip_radii.hpp"
#include "probecomp/registration/icp.hpp"

namespace probecomp::compensation::detail {

// A length in mm as printed: three significant figures (%.3g); um: a length in mm in micrometres, with its unit.
std::string mm(double v);
std::string um(double v_mm);

// The stop reason of a face that was not fitted (fit_faces) ends with kOffsetAlongNominal, and starts with
// kNotFitted where it held too few points; the warning that lists such faces takes both off (unfitted_face_warnings).
inline constexpr const char* kNotFitted = "not fitted: ";
inline constexpr const char* kOffsetAlongNominal = "; its points are offset along the nominal normal";

// What the user must know about a registration: its notes, an iteration limit reached, and the motions the data
// do not fix (held at the start: the deviations are blind to them).
void registration_warnings(const registration::RegistrationResult& r, std::vector<std::string>& warnings);

// Faces that hold points but were not fitted, and why (the user can measure more there): one warning, the faces
// with the most points first, at most kListedFaces of them by name.
void unfitted_face_warnings(const std::vector<FaceReport>& faces, std::vector<std::string>& warnings);

// Fitted faces that bend tighter than the tip somewhere: their radius offset folds over there and is left as its first
// fit, which can be millimetres off (fitting/offset.hpp, FoldsOver); the registration and the fit start from it. One
// warning per face, with the tightest radius, where, and how far the offset is off.
void folded_offset_warnings(const PreparedModel& prepared, const std::vector<FaceReport>& faces,
                            std::vector<std::string>& warnings);

// Rows whose u is mostly the doubt about the fit's normal next to points left out or between scan lines
// (compensation/normal_support.hpp), or across scan lines where nothing was measured (compensation/scan_lines.hpp):
// one warning per face and cause, with the largest angle and what it makes.
void normal_warnings(const FitResult& fits, const geometry::TipRadii& radii, std::span<const CompensatedPoint> points,
                     std::vector<std::string>& warnings);

// Faces whose outliers lie side by side (each among another's kGroupNeighbours nearest centres of the face), in
// groups of kMinGroup (5) or more: gross errors are single readings, seldom each other's neighbours, and such groups are
// more often shape the fit does not follow (a crease, a feature narrower than the points' spacing), whose readings
// are right. One warning per such face: how many, the largest group and where (`raw`: the centres, machine frame).
void outlier_group_warnings(const FitResult& fits, std::span<const Point3> raw, std::span<const CompensatedPoint> points,
                            std::vector<std::string>& warnings);

}  // namespace probecomp::compensation::detail
