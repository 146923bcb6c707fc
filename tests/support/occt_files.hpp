#pragma once
// CAD files read by OpenCASCADE alone, as the independent reference the CAD tests compare with.

#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>

#include <filesystem>
#include <vector>

namespace probecomp::testing {

// The file's shape as OpenCASCADE's STEP or IGES reader gives it (in millimetres, its default).
[[nodiscard]] TopoDS_Shape read_with_occt(const std::filesystem::path& path);
// The shape's faces in explorer order: the order the model promises.
[[nodiscard]] std::vector<TopoDS_Face> faces_of(const TopoDS_Shape& shape);

}  // namespace probecomp::testing
