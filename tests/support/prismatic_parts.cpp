#include "support/prismatic_parts.hpp"

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRep_Tool.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <Geom_Curve.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <STEPControl_Writer.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Vertex.hxx>
#include <gp_Ax2.hxx>

#include <cmath>
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

cad::Model filleted_boss() {
  const TopoDS_Shape cylinder = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 25, 30).Shape();
  BRepFilletAPI_MakeFillet fillet(cylinder);
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(cylinder, TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) {
    const TopoDS_Edge& edge = TopoDS::Edge(edges(i));
    double first = 0.0, last = 0.0;
    const Handle(Geom_Curve) curve = BRep_Tool::Curve(edge, first, last);
    // The top circle: every point of it at z = 30 (the seam runs from z = 0 to 30).
    if (!curve.IsNull() && std::abs(curve->Value(first).Z() - 30) < 1e-9 && std::abs(curve->Value((first + last) / 2).Z() - 30) < 1e-9) {
      fillet.Add(12, edge);
    }
  }
  fillet.Build();
  if (!fillet.IsDone()) throw std::runtime_error("OpenCASCADE could not round the boss's top edge");
  return through_step(fillet.Shape(), "filleted_boss");
}

cad::Model block_with_hole() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 60, 40, 20).Shape();
  const TopoDS_Shape pin = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(40, 20, -1), gp_Dir(0, 0, 1)), 5, 22).Shape();
  BRepAlgoAPI_Cut cut(box, pin);
  if (!cut.IsDone()) throw std::runtime_error("OpenCASCADE could not cut the hole");
  return through_step(cut.Shape(), "block_with_hole");
}

BlockWithHoleFaces faces_of_block_with_hole(const cad::Model& model) {
  return {.bottom = face_through(model, Point3(10, 10, 0)),
          .front = face_through(model, Point3(10, 0, 10)),
          .left = face_through(model, Point3(0, 10, 10)),
          .top = face_through(model, Point3(10, 10, 20)),
          .right = face_through(model, Point3(60, 10, 10)),
          .back = face_through(model, Point3(10, 40, 10)),
          .hole = face_through(model, Point3(45, 20, 10))};
}

cad::Model block_with_countersink() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 60, 40, 20).Shape();
  const TopoDS_Shape cone = BRepPrimAPI_MakeCone(gp_Ax2(gp_Pnt(30, 20, 12), gp_Dir(0, 0, 1)), 4, 9, 9).Shape();
  BRepAlgoAPI_Cut cut(box, cone);
  if (!cut.IsDone()) throw std::runtime_error("OpenCASCADE could not cut the countersink");
  return through_step(cut.Shape(), "block_with_countersink");
}

cad::Model block_with_pin() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 40, 10).Shape();
  const TopoDS_Shape pin = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 20, 10), gp_Dir(0, 0, 1)), 4, 12).Shape();
  BRepAlgoAPI_Fuse fuse(box, pin);
  if (!fuse.IsDone()) throw std::runtime_error("OpenCASCADE could not fuse the pin");
  return through_step(fuse.Shape(), "block_with_pin");
}

cad::Model l_block_with_fillet(double fillet_radius) {
  const TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 20, 20).Shape();
  // The cut overshoots the block in x, y and z so that no face of the cut coincides with one of the block.
  const TopoDS_Shape notch = BRepPrimAPI_MakeBox(gp_Pnt(10, -1, 10), 31, 22, 11).Shape();
  BRepAlgoAPI_Cut cut(block, notch);
  if (!cut.IsDone()) throw std::runtime_error("OpenCASCADE could not cut the notch");
  BRepFilletAPI_MakeFillet fillet(cut.Shape());
  int edges = 0;
  // Each edge once (an explorer meets it once per face).
  TopTools_IndexedMapOfShape all;
  TopExp::MapShapes(cut.Shape(), TopAbs_EDGE, all);
  for (int e = 1; e <= all.Extent(); ++e) {
    const TopoDS_Edge& edge = TopoDS::Edge(all(e));
    const gp_Pnt a = BRep_Tool::Pnt(TopExp::FirstVertex(edge)), b = BRep_Tool::Pnt(TopExp::LastVertex(edge));
    const bool on_corner = std::abs(a.X() - 10) < 1e-9 && std::abs(a.Z() - 10) < 1e-9 && std::abs(b.X() - 10) < 1e-9 &&
                           std::abs(b.Z() - 10) < 1e-9;
    if (on_corner) {
      fillet.Add(fillet_radius, edge);
      ++edges;
    }
  }
  if (edges != 1) throw std::runtime_error("the L block has " + std::to_string(edges) + " concave edges, not 1");
  fillet.Build();
  if (!fillet.IsDone()) throw std::runtime_error("OpenCASCADE could not round the concave edge");
  return through_step(fillet.Shape(), "l_block_with_fillet");
}

int face_through(const cad::Model& model, const Point3& p) {
  const cad::ModelLocator locator(model);
  const cad::ModelPoint foot = locator.closest_point(p);
  if (!foot.ok() || std::abs(foot.distance) > 1e-6) throw std::runtime_error("no face passes through the point");
  return foot.face;
}

}  // namespace probecomp::testing
