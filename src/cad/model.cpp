#include "probecomp/cad/model.hpp"

#include "exchange.hpp"

#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRep_Builder.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <GeomConvert.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <gp_Cone.hxx>
#include <gp_Cylinder.hxx>
#include <gp_Pln.hxx>
#include <gp_Sphere.hxx>
#include <gp_Torus.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESControl_Writer.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESEntity.hxx>
#include <IGESData_IGESModel.hxx>
#include <IGESData_IGESWriter.hxx>
#include <IGESData_Protocol.hxx>
#include <IGESSelect_WorkLibrary.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Interface_ReportEntity.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Precision.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_ErrorHandler.hxx>
#include <Standard_Failure.hxx>
#include <StepRepr_RepresentationItem.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <Transfer_TransientProcess.hxx>
#include <XSControl_Reader.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <fstream>
#include <mutex>
#include <optional>

#include "probecomp/cad/iges_counts.hpp"
#include "probecomp/occt/convert.hpp"
#include "probecomp/occt/crash_guard.hpp"
#include "probecomp/temporary_files.hpp"

namespace probecomp::cad {

using detail::fail;

namespace {

// Boundary polygons follow their pcurves to this fraction of the face's parameter range: on a 100 mm face
// that is about 1 µm, so membership is wrong only in a sliver of that width along the boundary.
constexpr double kTrimChordFraction = 1e-5;
// A face whose single boundary loop encloses its whole parameter domain to this relative area is untrimmed.
constexpr double kUntrimmedAreaFraction = 1e-7;

enum class Format { Step, Iges };

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

Format format_of(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".stp" || ext == ".step") return Format::Step;
  if (ext == ".igs" || ext == ".iges") return Format::Iges;
  fail(path, "unknown CAD format '" + ext + "' (expected .stp, .step, .igs or .iges)");
}

// OpenCASCADE's readers accept damaged files silently and return what they could read: check the frame of
// the file first, so that a truncated or foreign file is reported as such rather than as a smaller model.
void check_file_frame(const std::filesystem::path& path, Format format) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not a CAD file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot be opened for reading");
  // Only the first and last few kilobytes carry the frame; OpenCASCADE reads the whole file afterwards.
  constexpr std::streamoff kFrameBytes = 4096;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size <= 0) fail(path, "is empty");
  auto read_at = [&](std::streamoff offset, std::streamoff count) {
    std::string bytes(static_cast<std::size_t>(count), '\0');
    in.seekg(offset);
    in.read(bytes.data(), count);
    return bytes;
  };
  const std::string head = read_at(0, std::min(size, kFrameBytes));
  const std::string tail = read_at(std::max<std::streamoff>(0, size - kFrameBytes), std::min(size, kFrameBytes));
  auto last_line = [&] {
    const std::size_t end = tail.find_last_not_of(" \t\r\n");
    if (end == std::string::npos) return std::string();
    const std::size_t newline = tail.rfind('\n', end);
    const std::size_t begin = newline == std::string::npos ? 0 : newline + 1;
    return tail.substr(begin, end + 1 - begin);
  };
  if (format == Format::Step) {
    const std::size_t start = head.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || head.compare(start, 13, "ISO-10303-21;") != 0) fail(path, "not a STEP file (no ISO-10303-21 header)");
    if (tail.find("END-ISO-10303-21;") == std::string::npos) fail(path, "truncated STEP file (no END-ISO-10303-21; at the end)");
  } else {
    // IGES: fixed 80-column records, the section letter in column 73; the first record is in S (start) or,
    // rarely, G; the last is the T (terminate) record.
    const std::string first = head.substr(0, head.find('\n'));
    if (first.size() < 73 || (first[72] != 'S' && first[72] != 'G')) fail(path, "not an IGES file (no start section)");
    const std::string last = last_line();
    if (last.size() < 73 || last[72] != 'T') fail(path, "truncated IGES file (no terminate section at the end)");
  }
}

std::string unit_name(std::string raw) {
  raw = lower(raw);
  raw.erase(std::remove(raw.begin(), raw.end(), '.'), raw.end());
  if (raw.find("milli") != std::string::npos || raw == "mm") return "mm";
  if (raw.find("micro") != std::string::npos || raw == "um") return "um";
  if (raw.find("centi") != std::string::npos || raw == "cm") return "cm";
  if (raw.find("kilo") != std::string::npos || raw == "km") return "km";
  if (raw == "in" || raw == "inch" || raw == "inches") return "inch";
  if (raw == "ft" || raw == "foot" || raw == "feet") return "ft";
  if (raw == "m" || raw == "metre" || raw == "meter") return "m";
  return raw.empty() ? "unknown" : raw;
}

std::string iges_units(const IGESData_GlobalSection& g) {
  switch (g.UnitFlag()) {
    case 1: return "inch";
    case 2: return "mm";
    case 4: return "ft";
    case 5: return "mile";
    case 6: return "m";
    case 7: return "km";
    case 8: return "mil";
    case 9: return "um";
    case 10: return "cm";
    case 11: return "microinch";
    default: return g.UnitName().IsNull() ? "unknown" : unit_name(g.UnitName()->ToCString());
  }
}

std::string surface_type(const TopoDS_Face& face) {
  const Handle(Geom_Surface) s = BRep_Tool::Surface(face);
  if (s.IsNull()) return "none";
  switch (GeomAdaptor_Surface(s).GetType()) {
    case GeomAbs_Plane: return "plane";
    case GeomAbs_Cylinder: return "cylinder";
    case GeomAbs_Cone: return "cone";
    case GeomAbs_Sphere: return "sphere";
    case GeomAbs_Torus: return "torus";
    case GeomAbs_BezierSurface: return "bezier";
    case GeomAbs_BSplineSurface: return "bspline";
    case GeomAbs_SurfaceOfRevolution: return "revolution";
    case GeomAbs_SurfaceOfExtrusion: return "extrusion";
    case GeomAbs_OffsetSurface: return "offset";
    default: return "other";
  }
}

Vector3 to_vector(const gp_Dir& d) { return {d.X(), d.Y(), d.Z()}; }

// The face's surface in closed form, as the file gives it (with the face's location applied), for the elementary
// types; none for others.
std::optional<ElementarySurface> elementary_surface(const TopoDS_Face& face) {
  const Handle(Geom_Surface) s = BRep_Tool::Surface(face);
  if (s.IsNull()) return std::nullopt;
  const GeomAdaptor_Surface adaptor(s);
  ElementarySurface e;
  auto set_frame = [&e](const gp_Ax3& frame) {
    e.origin = Point3(frame.Location().X(), frame.Location().Y(), frame.Location().Z());
    e.x = to_vector(frame.XDirection());
    e.y = to_vector(frame.YDirection());
    e.z = to_vector(frame.Direction());
  };
  switch (adaptor.GetType()) {
    case GeomAbs_Plane: e.kind = ElementaryKind::Plane; set_frame(adaptor.Plane().Position()); return e;
    case GeomAbs_Cylinder: {
      const gp_Cylinder c = adaptor.Cylinder();
      e.kind = ElementaryKind::Cylinder;
      set_frame(c.Position());
      e.radius = c.Radius();
      return e;
    }
    case GeomAbs_Cone: {
      const gp_Cone c = adaptor.Cone();
      e.kind = ElementaryKind::Cone;
      set_frame(c.Position());
      e.radius = c.RefRadius();
      e.half_angle = c.SemiAngle();
      return e;
    }
    case GeomAbs_Sphere: {
      const gp_Sphere c = adaptor.Sphere();
      e.kind = ElementaryKind::Sphere;
      set_frame(c.Position());
      e.radius = c.Radius();
      return e;
    }
    case GeomAbs_Torus: {
      const gp_Torus c = adaptor.Torus();
      e.kind = ElementaryKind::Torus;
      set_frame(c.Position());
      e.radius = c.MajorRadius();
      e.minor_radius = c.MinorRadius();
      return e;
    }
    default: return std::nullopt;
  }
}

nurbs::Curve to_curve(const Handle(Geom2d_BSplineCurve)& in) {
  Handle(Geom2d_BSplineCurve) c = in;
  // Clamped as occt::from_occt clamps a surface: made non-periodic, then cut to its range where its end knots are
  // fewer than p + 1 (knot insertion, exact).
  auto unclamped = [](const Handle(Geom2d_BSplineCurve)& b) {
    return b->Multiplicity(1) < b->Degree() + 1 || b->Multiplicity(b->NbKnots()) < b->Degree() + 1;
  };
  if (c->IsPeriodic() || unclamped(c)) {
    c = Handle(Geom2d_BSplineCurve)::DownCast(in->Copy());
    if (c->IsPeriodic()) c->SetNotPeriodic();
    if (unclamped(c)) c->Segment(c->FirstParameter(), c->LastParameter());
  }
  TColStd_Array1OfReal flat(1, c->NbPoles() + c->Degree() + 1);
  c->KnotSequence(flat);
  std::vector<double> U(flat.begin(), flat.end());
  std::vector<HomogeneousPoint> Pw(static_cast<std::size_t>(c->NbPoles()));
  for (int i = 1; i <= c->NbPoles(); ++i) {
    const gp_Pnt2d P = c->Pole(i);
    const double w = c->Weight(i);
    Pw[static_cast<std::size_t>(i - 1)] << w * P.X(), w * P.Y(), 0.0, w;
  }
  return nurbs::Curve(nurbs::KnotVector(std::move(U), c->Degree()), std::move(Pw));
}

// B-spline, Bézier and plane faces convert to NURBS without changing their parametrisation, so their pcurves
// stay valid as they are. Others (cylinders, cones, revolutions, ...) are reparametrised by OpenCASCADE's
// NURBS conversion, which rewrites their pcurves to match; it is done per face because it is slow (it
// recomputes tolerances), and the impeller's 277 B-spline faces would take seconds for nothing.
TopoDS_Face as_nurbs_face(const TopoDS_Face& face, const std::string& type) {
  if (type == "bspline" || type == "bezier" || type == "plane") return face;
  BRepBuilderAPI_NurbsConvert convert(face, Standard_True);
  return TopoDS::Face(convert.Shape());
}

nurbs::Surface face_surface(const std::filesystem::path& path, int index, const TopoDS_Face& face) {
  // BRep_Tool::Surface applies the face's location: the surface comes back in the model's frame.
  Handle(Geom_Surface) s = BRep_Tool::Surface(face);
  double b[4] = {0.0, 0.0, 0.0, 0.0};
  if (!s.IsNull()) s->Bounds(b[0], b[1], b[2], b[3]);
  if (!s.IsNull() && std::any_of(b, b + 4, [](double x) { return Precision::IsInfinite(x); })) {
    // An unbounded surface (a plane) becomes the patch over the face's parameter range.
    double u0 = 0.0, u1 = 0.0, v0 = 0.0, v1 = 0.0;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    s = new Geom_RectangularTrimmedSurface(s, u0, u1, v0, v1);
  }
  Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(s);
  if (bs.IsNull() && !s.IsNull()) bs = GeomConvert::SurfaceToBSplineSurface(s);
  if (bs.IsNull()) fail(path, "face " + std::to_string(index) + " has no surface that converts to NURBS");
  if (bs->UDegree() > nurbs::kMaxDegree || bs->VDegree() > nurbs::kMaxDegree) {
    fail(path, "face " + std::to_string(index) + " has degree " + std::to_string(std::max(bs->UDegree(), bs->VDegree())) +
                   ", above the supported " + std::to_string(nurbs::kMaxDegree));
  }
  return occt::from_occt(bs);
}

std::shared_ptr<const Trim> face_trim(const TopoDS_Face& face, const nurbs::Surface& surface) {
  const nurbs::Domain dom = surface.domain();
  const double tol = kTrimChordFraction * std::max(dom.u1 - dom.u0, dom.v1 - dom.v0);
  std::vector<BoundaryCurve> curves;
  int wires = 0;
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) ++wires;
  for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next()) {
    const TopoDS_Edge& edge = TopoDS::Edge(e.Current());
    double first = 0.0, last = 0.0;
    const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, first, last);
    if (pc.IsNull() || !(last > first)) continue;
    const Handle(Geom2d_BSplineCurve) bc = Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pc, first, last));
    BoundaryCurve curve{to_curve(bc), {}, edge.Orientation() == TopAbs_REVERSED};
    curve.t = boundary_samples(curve.uv, tol);
    curves.push_back(std::move(curve));
  }
  if (curves.empty()) return nullptr;
  auto trim = std::make_shared<const Trim>(std::move(curves));
  const double domain_area = (dom.u1 - dom.u0) * (dom.v1 - dom.v0);
  if (wires == 1 && std::abs(trim->parameter_area() - domain_area) <= kUntrimmedAreaFraction * domain_area) return nullptr;
  return trim;
}

std::string face_name(const Handle(XSControl_TransferReader)& tr, const TopoDS_Face& face, Format format) {
  if (tr.IsNull()) return {};
  const Handle(Standard_Transient) entity = tr->EntityFromShapeResult(face, 1);
  if (entity.IsNull()) return {};
  if (format == Format::Step) {
    const auto item = Handle(StepRepr_RepresentationItem)::DownCast(entity);
    if (!item.IsNull() && !item->Name().IsNull()) return item->Name()->ToCString();
  } else {
    const auto e = Handle(IGESData_IGESEntity)::DownCast(entity);
    if (!e.IsNull() && e->HasName() && !e->NameValue().IsNull()) return e->NameValue()->ToCString();
    if (!e.IsNull() && e->HasShortLabel()) return e->ShortLabel()->ToCString();
  }
  return {};
}

// What the exchange reader gives back: the shape, the transfer record (for face names) and the file's length unit.
struct ExchangeRead {
  TopoDS_Shape shape;
  Handle(XSControl_TransferReader) transfer;
  std::string file_units;
  std::vector<std::string> warnings;
};

// An entity OpenCASCADE left out, as a user can find it in the file ("#114 B_SPLINE_SURFACE_WITH_KNOTS",
// "D171 104 2 ConicArc") where the file holds it, and the first failure its check records. IGES type names and
// OpenCASCADE's messages come padded: one space between words.
std::string named_failure(const Interface_InterfaceModel& file, const Handle(Standard_Transient)& entity,
                          const Interface_Check& check) {
  std::string text;
  if (!entity.IsNull() && file.Contains(entity)) {
    const Handle(TCollection_HAsciiString) label = file.StringLabel(entity);
    text = std::string(label.IsNull() ? "?" : label->ToCString()) + " " + file.TypeName(entity) + ": ";
  }
  if (check.NbFails() > 0) text += check.CFail(1);
  text.erase(std::unique(text.begin(), text.end(), [](char a, char b) { return a == ' ' && b == ' '; }), text.end());
  return text;
}

// OpenCASCADE reads past entities it cannot parse (a broken reference, a wrong type) and leaves them out of
// the shape; that must not go unsaid. Files from real systems have such errors too (tail_section has four
// angle units), so it is a warning, not a refusal: the faces read are checked as any others.
std::vector<std::string> entity_errors(const Interface_InterfaceModel& file) {
  int errors = 0;
  std::string first;
  for (int i = 1; i <= file.NbEntities(); ++i) {
    if (!file.IsErrorEntity(i)) continue;
    if (errors++ > 0) continue;
    const Handle(Interface_ReportEntity) report = file.ReportEntity(i);
    first = named_failure(file, report->Concerned(), *report->Check());
  }
  std::vector<std::string> out;
  if (errors > 0) {
    out.push_back("OpenCASCADE found errors in " + std::to_string(errors) + " of the file's " +
                  std::to_string(file.NbEntities()) + " entities and left them out (first: " + first + ")");
  }
  if (file.GlobalCheck()->HasFailed()) {
    out.push_back(std::string("OpenCASCADE found the file malformed: ") + file.GlobalCheck()->CFail(1));
  }
  return out;
}

// Entities that parsed but whose conversion failed (an exception, or a crash CrashGuard turned into one, caught by
// OpenCASCADE's transfer itself) are missing from the shape too. Of tests/data/cad, only iges_spec_nentity.igs has one.
std::optional<std::string> transfer_failures(const Interface_InterfaceModel& file, const XSControl_TransferReader& transfer) {
  int failed = 0;
  std::string first;
  for (Interface_CheckIterator c = transfer.TransientProcess()->CheckList(false); c.More(); c.Next()) {
    if (c.Value()->HasFailed() && failed++ == 0) first = named_failure(file, c.Value()->Entity(), *c.Value());
  }
  if (failed == 0) return std::nullopt;
  return "OpenCASCADE could not convert " + std::to_string(failed) + " of the file's entities and left " +
         (failed == 1 ? "it" : "them") + " out (first: " + first + ")";
}

ExchangeRead read_exchange_file(const std::filesystem::path& path, Format format) {
  ExchangeRead out;
  // The readers live outside the try so that a crash turned into a Standard_Failure (occt::CrashGuard, which
  // jumps back to OCC_CATCH_SIGNALS and throws there) still destroys them.
  std::optional<STEPControl_Reader> step;
  std::optional<IGESControl_Reader> iges;
  if (format == Format::Step) step.emplace(); else iges.emplace();
  XSControl_Reader& reader = step ? static_cast<XSControl_Reader&>(*step) : *iges;
  try {
    OCC_CATCH_SIGNALS
    // Counts beyond what the file holds would have OpenCASCADE allocate for them (cad/iges_counts.hpp). Its lexer
    // runs here, under the exchange lock and the crash guard, as it does again inside ReadFile.
    if (iges) {
      if (std::optional<std::string> r = iges_count_beyond_data(path)) fail(path, *r + ": the file is damaged");
    }
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) {
      fail(path, format == Format::Step ? "OpenCASCADE cannot read it as STEP" : "OpenCASCADE cannot read it as IGES");
    }
    if (step) {
      TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
      step->FileUnits(lengths, angles, solid_angles);
      out.file_units = lengths.IsEmpty() ? "unknown" : unit_name(lengths.First().ToCString());
    } else {
      out.file_units = iges_units(iges->IGESModel()->GlobalSection());
    }
    out.warnings = entity_errors(*reader.Model());
    reader.TransferRoots();
    out.shape = reader.OneShape();
    out.transfer = reader.WS()->TransferReader();
    if (std::optional<std::string> w = transfer_failures(*reader.Model(), *out.transfer)) out.warnings.push_back(*w);
  } catch (const Standard_Failure& e) {
    fail(path, std::string("OpenCASCADE failed while reading it: ") + e.GetMessageString());
  }
  return out;
}

}  // namespace

namespace detail {

// OpenCASCADE's exchange settings are process-wide statics: set them once, and serialise reads.
std::mutex& exchange_mutex() {
  static std::mutex m;
  return m;
}

void fail(const std::filesystem::path& path, const std::string& cause) { throw CadError(path.string() + ": " + cause); }

void configure_exchange() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Quiet: our errors are our own one-line messages, not OpenCASCADE's trace on standard output.
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_Printer));
    IGESControl_Controller::Init();
    // Every length read is converted to millimetres (OpenCASCADE's default, set here so it is not assumed).
    Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  });
}

}  // namespace detail

using detail::configure_exchange;
using detail::exchange_mutex;

Model Model::load(const std::filesystem::path& path) { return read_model(path); }

Model read_model(const std::filesystem::path& path) {
  const Format format = format_of(path);
  check_file_frame(path, format);
  configure_exchange();
  std::lock_guard lock(exchange_mutex());
  const occt::CrashGuard crash_guard;

  Model model;
  model.path = path;
  ExchangeRead read = read_exchange_file(path, format);
  model.file_units = std::move(read.file_units);
  model.read_warnings = std::move(read.warnings);
  const TopoDS_Shape& shape = read.shape;
  const Handle(XSControl_TransferReader)& transfer = read.transfer;
  if (shape.IsNull()) fail(path, "no surfaces in the file");

  TopTools_IndexedMapOfShape solid_faces;
  for (TopExp_Explorer s(shape, TopAbs_SOLID); s.More(); s.Next()) TopExp::MapShapes(s.Current(), TopAbs_FACE, solid_faces);

  std::vector<TopoDS_Face> faces;
  for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) faces.push_back(TopoDS::Face(f.Current()));
  if (faces.empty()) fail(path, "no surfaces in the file");

  try {
    OCC_CATCH_SIGNALS
    for (std::size_t k = 0; k < faces.size(); ++k) {
      const TopoDS_Face& original = faces[k];
      const int index = static_cast<int>(k);
      const std::string type = surface_type(original);
      const TopoDS_Face nurbs_face = as_nurbs_face(original, type);
      Face face{index, face_name(transfer, original, format), type, face_surface(path, index, nurbs_face), nullptr, 1, false};
      face.trim = face_trim(nurbs_face, face.surface);
      face.exact = type != "offset" && type != "other";
      face.outward = original.Orientation() == TopAbs_REVERSED ? -1 : 1;
      face.material_known = solid_faces.Contains(original);
      if (const std::optional<ElementarySurface> e = elementary_surface(original)) face.analytic = make_analytic_face(*e, face.surface);
      model.faces.push_back(std::move(face));
    }
  } catch (const Standard_Failure& e) {
    fail(path, std::string("OpenCASCADE failed converting faces to NURBS: ") + e.GetMessageString());
  } catch (const nurbs::InvalidGeometry& e) {
    fail(path, std::string("a face converted to invalid NURBS: ") + e.what());
  }
  return model;
}

void write_surfaces(const std::filesystem::path& path, const std::vector<nurbs::Surface>& surfaces) {
  const Format format = format_of(path);
  configure_exchange();
  std::lock_guard lock(exchange_mutex());
  std::filesystem::path tmp = path;
  tmp += ".partial";
  const TemporaryFile interrupt_removes(tmp);
  bool ok = false;
  errno = 0;
  try {
    if (format == Format::Iges) {
      IGESControl_Writer writer("MM", 0);
      for (const nurbs::Surface& s : surfaces) writer.AddGeom(occt::to_occt(s));
      writer.ComputeModel();
      // OpenCASCADE's default real format keeps too few digits for a 1e-9 mm round trip; 17 significant digits
      // reproduce every double exactly.
      IGESData_IGESWriter iw(writer.Model());
      iw.FloatWriter().SetFormat("%.16E");
      iw.SendModel(IGESSelect_WorkLibrary::DefineProtocol());
      std::ofstream out(tmp, std::ios::binary);
      ok = iw.Print(out) && static_cast<bool>(out.flush());
    } else {
      BRep_Builder builder;
      TopoDS_Compound compound;
      builder.MakeCompound(compound);
      for (const nurbs::Surface& s : surfaces) {
        builder.Add(compound, BRepBuilderAPI_MakeFace(occt::to_occt(s), Precision::Confusion()).Face());
      }
      Interface_Static::SetCVal("write.step.unit", "MM");
      STEPControl_Writer writer;
      ok = writer.Transfer(compound, STEPControl_AsIs) == IFSelect_RetDone && writer.Write(tmp.c_str()) == IFSelect_RetDone;
    }
  } catch (const Standard_Failure& e) {
    ok = false;
  }
  const int reason = errno;  // of the failing open(2) or write(2), if that is what failed
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(tmp, ec);
    fail(path, "could not be written" + system_reason(reason));
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    fail(path, "could not be written: " + ec.message());
  }
}

}  // namespace probecomp::cad
