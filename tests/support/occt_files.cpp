#include "support/occt_files.hpp"

#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <stdexcept>

namespace probecomp::testing {

TopoDS_Shape read_with_occt(const std::filesystem::path& path) {
  if (path.extension() == ".stp") {
    STEPControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("OpenCASCADE cannot read " + path.string());
    reader.TransferRoots();
    return reader.OneShape();
  }
  IGESControl_Controller::Init();
  IGESControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("OpenCASCADE cannot read " + path.string());
  reader.TransferRoots();
  return reader.OneShape();
}

std::vector<TopoDS_Face> faces_of(const TopoDS_Shape& shape) {
  std::vector<TopoDS_Face> faces;
  for (TopExp_Explorer e(shape, TopAbs_FACE); e.More(); e.Next()) faces.push_back(TopoDS::Face(e.Current()));
  return faces;
}

}  // namespace probecomp::testing
