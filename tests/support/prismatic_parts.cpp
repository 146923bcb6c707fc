#include "support/prismatic_parts.hpp"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPControl_Writer.hxx>
#include <gp_Ax2.hxx>

#include <filesystem>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "probecomp/cad/locator.hpp"

namespace probecomp::testing {

namespace {

// The shape through a STEP file, as a user's CAD file comes.
cad::Model through_step(const TopoDS_Shape& shape, const std::string& name) {
  // One file per process: tests may run in parallel.
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("probecomp_" + name + "_" + std::to_string(::getpid()) + ".stp");
  // Quiet, as the readers are: no transfer statistics on standard output.
  Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
  Interface_Static::SetCVal("write.step.unit", "MM");
  STEPControl_Writer writer;
  if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone || writer.Write(path.c_str()) != IFSelect_RetDone) {
    throw std::runtime_error("OpenCASCADE could not write " + path.string());
  }
  cad::Model model = cad::Model::load(path);
  std::filesystem::remove(path);
  return model;
}

}  // namespace

cad::Model block_with_hole() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 60, 40, 20).Shape();
  const TopoDS_Shape pin = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(40, 20, -1), gp_Dir(0, 0, 1)), 5, 22).Shape();
  BRepAlgoAPI_Cut cut(box, pin);
  if (!cut.IsDone()) throw std::runtime_error("OpenCASCADE could not cut the hole");
  return through_step(cut.Shape(), "block_with_hole");
}

cad::Model block_with_pin() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 40, 10).Shape();
  const TopoDS_Shape pin = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 20, 10), gp_Dir(0, 0, 1)), 4, 12).Shape();
  BRepAlgoAPI_Fuse fuse(box, pin);
  if (!fuse.IsDone()) throw std::runtime_error("OpenCASCADE could not fuse the pin");
  return through_step(fuse.Shape(), "block_with_pin");
}

int face_through(const cad::Model& model, const Point3& p) {
  const cad::ModelLocator locator(model);
  const cad::ModelPoint foot = locator.closest_point(p);
  if (!foot.ok() || std::abs(foot.distance) > 1e-6) throw std::runtime_error("no face passes through the point");
  return foot.face;
}

}  // namespace probecomp::testing
