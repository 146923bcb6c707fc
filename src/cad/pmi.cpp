#include "probecomp/cad/pmi.hpp"

#include <BRep_Builder.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <Standard_ErrorHandler.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_DataMapOfShapeInteger.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDimTolObjects_DatumObject.hxx>
#include <XCAFDimTolObjects_GeomToleranceObject.hxx>
#include <XCAFDoc_Datum.hxx>
#include <XCAFDoc_DimTolTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_GeomTolerance.hxx>
#include <XCAFDoc_ShapeTool.hxx>

#include <algorithm>
#include <cctype>
#include <map>
#include <mutex>
#include <set>

#include "probecomp/error.hpp"
#include "probecomp/occt/crash_guard.hpp"

#include "exchange.hpp"

namespace probecomp::cad {

namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& why) {
  throw CadError(path.string() + ": " + why);
}

ToleranceType type_of(XCAFDimTolObjects_GeomToleranceType t) {
  switch (t) {
    case XCAFDimTolObjects_GeomToleranceType_Angularity: return ToleranceType::Angularity;
    case XCAFDimTolObjects_GeomToleranceType_CircularRunout: return ToleranceType::CircularRunout;
    case XCAFDimTolObjects_GeomToleranceType_CircularityOrRoundness: return ToleranceType::Circularity;
    case XCAFDimTolObjects_GeomToleranceType_Coaxiality: return ToleranceType::Coaxiality;
    case XCAFDimTolObjects_GeomToleranceType_Concentricity: return ToleranceType::Concentricity;
    case XCAFDimTolObjects_GeomToleranceType_Cylindricity: return ToleranceType::Cylindricity;
    case XCAFDimTolObjects_GeomToleranceType_Flatness: return ToleranceType::Flatness;
    case XCAFDimTolObjects_GeomToleranceType_Parallelism: return ToleranceType::Parallelism;
    case XCAFDimTolObjects_GeomToleranceType_Perpendicularity: return ToleranceType::Perpendicularity;
    case XCAFDimTolObjects_GeomToleranceType_Position: return ToleranceType::Position;
    case XCAFDimTolObjects_GeomToleranceType_ProfileOfLine: return ToleranceType::ProfileOfLine;
    case XCAFDimTolObjects_GeomToleranceType_ProfileOfSurface: return ToleranceType::ProfileOfSurface;
    case XCAFDimTolObjects_GeomToleranceType_Straightness: return ToleranceType::Straightness;
    case XCAFDimTolObjects_GeomToleranceType_Symmetry: return ToleranceType::Symmetry;
    case XCAFDimTolObjects_GeomToleranceType_TotalRunout: return ToleranceType::TotalRunout;
    default: return ToleranceType::Other;
  }
}

bool is_step(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".stp" || ext == ".step";
}

}  // namespace

const char* to_string(ToleranceType t) {
  switch (t) {
    case ToleranceType::Angularity: return "angularity";
    case ToleranceType::CircularRunout: return "circular runout";
    case ToleranceType::Circularity: return "circularity";
    case ToleranceType::Coaxiality: return "coaxiality";
    case ToleranceType::Concentricity: return "concentricity";
    case ToleranceType::Cylindricity: return "cylindricity";
    case ToleranceType::Flatness: return "flatness";
    case ToleranceType::Parallelism: return "parallelism";
    case ToleranceType::Perpendicularity: return "perpendicularity";
    case ToleranceType::Position: return "position";
    case ToleranceType::ProfileOfLine: return "profile of line";
    case ToleranceType::ProfileOfSurface: return "profile of surface";
    case ToleranceType::Straightness: return "straightness";
    case ToleranceType::Symmetry: return "symmetry";
    case ToleranceType::TotalRunout: return "total runout";
    case ToleranceType::Other: return "other";
  }
  return "other";
}

Pmi read_pmi(const std::filesystem::path& path, const Model& model) {
  Pmi out;
  if (!is_step(path)) return out;
  detail::configure_exchange();
  std::lock_guard lock(detail::exchange_mutex());
  const occt::CrashGuard crash_guard;
  try {
    OCC_CATCH_SIGNALS
    Handle(TDocStd_Document) doc;
    XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
    STEPCAFControl_Reader reader;
    reader.SetGDTMode(true);
    reader.SetNameMode(false);
    reader.SetColorMode(false);
    reader.SetLayerMode(false);
    if (reader.ReadFile(path.string().c_str()) != IFSelect_RetDone) fail(path, "OpenCASCADE cannot read it as STEP");
    if (!reader.Transfer(doc)) fail(path, "OpenCASCADE could not transfer its shapes and PMI");
    const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
    const Handle(XCAFDoc_DimTolTool) dimtol = XCAFDoc_DocumentTool::DimTolTool(doc->Main());

    // The faces in the order Model::load gives them: TopExp_Explorer over the one shape of the file's roots (a
    // compound of them where there are several, as STEPControl_Reader::OneShape makes it).
    TDF_LabelSequence free;
    shapes->GetFreeShapes(free);
    TopoDS_Shape root;
    if (free.Length() == 1) {
      root = shapes->GetShape(free.Value(1));
    } else {
      TopoDS_Compound c;
      BRep_Builder b;
      b.MakeCompound(c);
      for (int i = 1; i <= free.Length(); ++i) b.Add(c, shapes->GetShape(free.Value(i)));
      root = c;
    }
    TopTools_DataMapOfShapeInteger index;
    int count = 0;
    for (TopExp_Explorer f(root, TopAbs_FACE); f.More(); f.Next(), ++count) {
      if (!index.IsBound(f.Current())) index.Bind(f.Current(), count);
    }
    if (count != model.face_count()) {
      fail(path, "its PMI's shapes hold " + std::to_string(count) + " faces, the model " +
                     std::to_string(model.face_count()) + ": not the same file's faces");
    }

    std::set<std::string> names;
    TDF_LabelSequence datum_labels;
    dimtol->GetDatumLabels(datum_labels);
    for (int i = 1; i <= datum_labels.Length(); ++i) {
      Handle(XCAFDoc_Datum) d;
      if (datum_labels.Value(i).FindAttribute(XCAFDoc_Datum::GetID(), d) && !d->GetObject()->GetName().IsNull()) {
        names.insert(d->GetObject()->GetName()->String().ToCString());
      }
    }
    out.datums.assign(names.begin(), names.end());

    TDF_LabelSequence tolerance_labels;
    dimtol->GetGeomToleranceLabels(tolerance_labels);
    for (int i = 1; i <= tolerance_labels.Length(); ++i) {
      Handle(XCAFDoc_GeomTolerance) attr;
      if (!tolerance_labels.Value(i).FindAttribute(XCAFDoc_GeomTolerance::GetID(), attr)) continue;
      const Handle(XCAFDimTolObjects_GeomToleranceObject) object = attr->GetObject();
      GeometricTolerance t;
      t.type = type_of(object->GetType());
      TDF_LabelSequence first, second;
      dimtol->GetRefShapeLabel(tolerance_labels.Value(i), first, second);
      for (int k = 1; k <= first.Length(); ++k) {
        for (TopExp_Explorer f(shapes->GetShape(first.Value(k)), TopAbs_FACE); f.More(); f.Next()) {
          if (index.IsBound(f.Current())) t.faces.push_back(index.Find(f.Current()));
        }
      }
      std::sort(t.faces.begin(), t.faces.end());
      t.faces.erase(std::unique(t.faces.begin(), t.faces.end()), t.faces.end());
      // The reference frame: each datum once, by its position in it (primary 1, secondary 2, tertiary 3). Datum
      // targets (A1, A2, A3) come as their datum's name repeated.
      TDF_LabelSequence refs;
      dimtol->GetDatumOfTolerLabels(tolerance_labels.Value(i), refs);
      std::map<int, std::string> by_position;
      for (int k = 1; k <= refs.Length(); ++k) {
        Handle(XCAFDoc_Datum) d;
        if (!refs.Value(k).FindAttribute(XCAFDoc_Datum::GetID(), d) || d->GetObject()->GetName().IsNull()) continue;
        const std::string name = d->GetObject()->GetName()->String().ToCString();
        const int position = d->GetObject()->GetPosition();
        if (!by_position.contains(position)) by_position[position] = name;
      }
      for (const auto& [position, name] : by_position) {
        if (std::find(t.datums.begin(), t.datums.end(), name) == t.datums.end()) t.datums.push_back(name);
      }
      // A zero zone is meaningful only with a material condition (0 at MMC), but CTC-02's unread magnitudes come
      // back as 0 with their MMC modifiers too: a 0 is never taken for a zone, and the warning says which it may be.
      const double value = object->GetValue();
      if (value > 0.0) {
        t.value = value;
      } else {
        const bool material = object->GetMaterialRequirementModifier() != XCAFDimTolObjects_GeomToleranceMatReqModif_None;
        out.warnings.push_back("tolerance " + std::to_string(out.tolerances.size() + 1) + " (" + to_string(t.type) +
                               ", " + std::to_string(t.faces.size()) + " face" + (t.faces.size() == 1 ? "" : "s") +
                               "): its magnitude was not read (OpenCASCADE reads 0 where the file stores it in a " +
                               "complex entity" + (material ? "; or a zero zone at a material condition" : "") + ")");
      }
      out.tolerances.push_back(std::move(t));
    }
  } catch (const Standard_Failure& e) {
    fail(path, std::string("OpenCASCADE failed reading its PMI: ") + e.GetMessageString());
  }
  return out;
}

}  // namespace probecomp::cad
