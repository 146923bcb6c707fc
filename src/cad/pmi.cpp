#include "probecomp/cad/pmi.hpp"

#include <BRep_Builder.hxx>
#include <Interface_EntityIterator.hxx>
#include <Interface_Graph.hxx>
#include <Interface_InterfaceModel.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <StepAP242_ItemIdentifiedRepresentationUsage.hxx>
#include <StepDimTol_Datum.hxx>
#include <StepDimTol_DatumTarget.hxx>
#include <StepRepr_RepresentationItem.hxx>
#include <StepRepr_ShapeAspect.hxx>
#include <StepRepr_ShapeAspectRelationship.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TransferBRep.hxx>
#include <Transfer_TransientProcess.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>
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
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include "probecomp/error.hpp"
#include "probecomp/occt/crash_guard.hpp"
#include "probecomp/cad/locator.hpp"
#include "step_measures.hpp"

#include "exchange.hpp"

namespace probecomp::cad {

namespace {

using detail::fail;

// A point or line datum target's placement lies on a face of the file's own geometry, to the precision of its
// coordinates (STEP files write 10–15 digits) and the closest-point solver's (1e-9 mm): 1 µm takes the face it is on
// and no other.
constexpr double kTargetOnFace = 1e-3;
// A line datum target runs along its face: the cosine of its direction with the face's normal where it is placed is
// at most this (its directions written to 10–15 digits; FTC-06's are exact, 0).
constexpr double kTargetAlongFace = 1e-6;

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


// The datums' faces as the file's entities tie them, where XDE does not (OpenCASCADE 7.6 attaches few datums to
// shapes: of NIST FTC-06's ten, two). AP242 ties a datum to geometry in one of two ways: an item identified
// representation usage (a geometric item specific usage, mostly) whose definition is the datum itself, or one whose
// definition is a datum feature (or datum target) that a shape aspect relationship relates to the datum. Faces come from the items through the reader's transfer map;
// targets that are points, lines or circles (a target's description) have none and are counted.
struct EntityDatum {
  std::vector<TopoDS_Shape> shapes;
  int point_or_line_targets = 0, area_targets = 0;
};
std::map<std::string, EntityDatum> datums_from_entities(const STEPControl_Reader& reader) {
  std::map<std::string, EntityDatum> out;
  const Handle(XSControl_WorkSession) ws = reader.WS();
  const Handle(Interface_InterfaceModel) model = ws->Model();
  const Handle(Transfer_TransientProcess) process = ws->TransferReader()->TransientProcess();
  if (model.IsNull() || process.IsNull()) return out;
  std::vector<std::pair<Handle(StepDimTol_Datum), std::string>> datums;
  std::multimap<const Standard_Transient*, Handle(StepRepr_RepresentationItem)> items;  // usage: definition → item
  std::multimap<const Standard_Transient*, Handle(StepRepr_ShapeAspect)> relating;     // datum → its features
  for (int i = 1; i <= model->NbEntities(); ++i) {
    const Handle(Standard_Transient) e = model->Value(i);
    if (const auto datum = Handle(StepDimTol_Datum)::DownCast(e); !datum.IsNull() && !datum->Identification().IsNull()) {
      datums.emplace_back(datum, datum->Identification()->String().ToCString());
    } else if (const auto usage = Handle(StepAP242_ItemIdentifiedRepresentationUsage)::DownCast(e); !usage.IsNull()) {
      const Handle(Standard_Transient) definition = usage->Definition().Value();
      bool read = false;
      for (int k = 1; k <= usage->NbIdentifiedItem(); ++k) {
        if (usage->IdentifiedItemValue(k).IsNull()) continue;
        items.emplace(definition.get(), usage->IdentifiedItemValue(k));
        read = true;
      }
      if (!read) {
        // OpenCASCADE 7.6 reads one null item where the file gives them as a typed SET_REPRESENTATION_ITEM((...))
        // (NIST FTC-06's datums B and F, STC-08's B, E, G, H and J); the faces it references are still in the entity
        // graph.
        for (Interface_EntityIterator shared = ws->Graph().Shareds(e); shared.More(); shared.Next()) {
          if (const auto item = Handle(StepRepr_RepresentationItem)::DownCast(shared.Value()); !item.IsNull()) {
            items.emplace(definition.get(), item);
          }
        }
      }
    } else if (const auto r = Handle(StepRepr_ShapeAspectRelationship)::DownCast(e); !r.IsNull()) {
      if (!r->RelatedShapeAspect().IsNull() && !r->RelatingShapeAspect().IsNull()) {
        relating.emplace(r->RelatedShapeAspect().get(), r->RelatingShapeAspect());
      }
    }
  }
  for (const auto& [datum, name] : datums) {
    EntityDatum& d = out[name];
    std::vector<const Standard_Transient*> sources{datum.get()};
    for (auto [it, end] = relating.equal_range(datum.get()); it != end; ++it) {
      if (const auto target = Handle(StepDimTol_DatumTarget)::DownCast(it->second); !target.IsNull()) {
        const std::string kind = target->Description().IsNull() ? "" : target->Description()->String().ToCString();
        if (kind != "area" && kind != "rectangle" && kind != "circle") {
          ++d.point_or_line_targets;
          continue;
        }
        ++d.area_targets;
      }
      sources.push_back(it->second.get());
    }
    for (const Standard_Transient* source : sources) {
      for (auto [it, end] = items.equal_range(source); it != end; ++it) {
        const TopoDS_Shape shape = TransferBRep::ShapeResult(process, it->second);
        if (!shape.IsNull()) d.shapes.push_back(shape);
      }
    }
  }
  return out;
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

    // The faces a label (datum, tolerance) refers to, in the model's order.
    auto faces_of = [&](const TDF_Label& label, std::vector<int>& faces) {
      TDF_LabelSequence first, second;
      dimtol->GetRefShapeLabel(label, first, second);
      for (int k = 1; k <= first.Length(); ++k) {
        for (TopExp_Explorer f(shapes->GetShape(first.Value(k)), TopAbs_FACE); f.More(); f.Next()) {
          if (index.IsBound(f.Current())) faces.push_back(index.Find(f.Current()));
        }
      }
      std::sort(faces.begin(), faces.end());
      faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    };

    // A datum may come as several labels of one name: its feature, or each of its targets (each target's label
    // once for every tolerance that refers to it: NIST CTC-02).
    std::map<std::string, DatumFeature> features;
    struct PlacedTargets {
      std::map<int, DatumTarget> placed;  // by number, not yet on a face
      std::set<int> unplaced;             // targets without a place
    };
    std::map<std::string, PlacedTargets> targets;
    TDF_LabelSequence datum_labels;
    dimtol->GetDatumLabels(datum_labels);
    for (int i = 1; i <= datum_labels.Length(); ++i) {
      Handle(XCAFDoc_Datum) d;
      if (!datum_labels.Value(i).FindAttribute(XCAFDoc_Datum::GetID(), d) || d->GetObject()->GetName().IsNull()) continue;
      const Handle(XCAFDimTolObjects_DatumObject) object = d->GetObject();
      const std::string name = object->GetName()->String().ToCString();
      DatumFeature& feature = features[name];
      feature.name = name;
      const bool target = object->IsDatumTarget();
      const bool area = target && (object->GetDatumTargetType() == XCAFDimTolObjects_DatumTargetType_Area ||
                                   object->GetDatumTargetType() == XCAFDimTolObjects_DatumTargetType_Rectangle ||
                                   object->GetDatumTargetType() == XCAFDimTolObjects_DatumTargetType_Circle);
      if (target && !area) {
        PlacedTargets& t = targets[name];
        const int number = object->GetDatumTargetNumber();
        const XCAFDimTolObjects_DatumTargetType type = object->GetDatumTargetType();
        if (object->HasDatumTargetParams() &&
            (type == XCAFDimTolObjects_DatumTargetType_Point || type == XCAFDimTolObjects_DatumTargetType_Line)) {
          const gp_Ax2 axis = object->GetDatumTargetAxis();
          DatumTarget placed{.number = number, .point = Point3(axis.Location().X(), axis.Location().Y(), axis.Location().Z())};
          if (type == XCAFDimTolObjects_DatumTargetType_Line) {
            // Along the placement's axis: FTC-06's lines run so across their faces; its x direction leaves them.
            placed.direction = Vector3(axis.Direction().X(), axis.Direction().Y(), axis.Direction().Z());
            placed.length = object->GetDatumTargetLength();
          }
          t.placed.emplace(number, placed);
        } else {
          t.unplaced.insert(number);
        }
        continue;
      }
      if (area) ++feature.area_targets;
      faces_of(datum_labels.Value(i), feature.faces);
    }
    for (const auto& [name, entity] : datums_from_entities(reader.Reader())) {
      DatumFeature& feature = features[name];
      feature.name = name;
      feature.point_or_line_targets = std::max(feature.point_or_line_targets, entity.point_or_line_targets);
      feature.area_targets = std::max(feature.area_targets, entity.area_targets);
      for (const TopoDS_Shape& shape : entity.shapes) {
        for (TopExp_Explorer f(shape, TopAbs_FACE); f.More(); f.Next()) {
          if (index.IsBound(f.Current())) feature.faces.push_back(index.Find(f.Current()));
        }
      }
    }
    // Point targets on the faces they lie on; a target off every face is not used (and counted).
    std::optional<ModelLocator> locator;
    for (auto& [name, found] : targets) {
      DatumFeature& feature = features[name];
      for (auto& [number, target] : found.placed) {
        if (!locator) locator.emplace(model);
        const ModelPoint foot = locator->closest_point(target.point);
        // A line must run along its face: across the normal there.
        const bool along = !target.line() || std::abs(target.direction.dot(foot.normal)) <= kTargetAlongFace;
        if (foot.ok() && std::abs(foot.distance) <= kTargetOnFace && along && target.length >= 0.0) {
          target.face = foot.face;
          feature.targets.push_back(target);
          feature.faces.push_back(foot.face);
        } else {
          found.unplaced.insert(number);
        }
      }
      // The entity graph counts every point or line target; those placed here are taken.
      feature.point_or_line_targets = std::max(static_cast<int>(found.unplaced.size()),
                                               feature.point_or_line_targets - static_cast<int>(feature.targets.size()));
    }
    for (auto& [name, feature] : features) {
      std::sort(feature.faces.begin(), feature.faces.end());
      feature.faces.erase(std::unique(feature.faces.begin(), feature.faces.end()), feature.faces.end());
      out.datums.push_back(name);
      out.datum_features.push_back(std::move(feature));
    }

    TDF_LabelSequence tolerance_labels;
    dimtol->GetGeomToleranceLabels(tolerance_labels);
    const std::map<std::string, detail::ToleranceMeasures> measures = detail::tolerance_measures(path);
    for (int i = 1; i <= tolerance_labels.Length(); ++i) {
      Handle(XCAFDoc_GeomTolerance) attr;
      if (!tolerance_labels.Value(i).FindAttribute(XCAFDoc_GeomTolerance::GetID(), attr)) continue;
      const Handle(XCAFDimTolObjects_GeomToleranceObject) object = attr->GetObject();
      GeometricTolerance t;
      t.type = type_of(object->GetType());
      faces_of(tolerance_labels.Value(i), t.faces);
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
      // What the file's own text gives where OpenCASCADE reads nothing: matched by the tolerance's name.
      const detail::ToleranceMeasures* own = nullptr;
      if (!object->GetSemanticName().IsNull()) {
        const auto it = measures.find(object->GetSemanticName()->ToCString());
        if (it != measures.end()) own = &it->second;
      }
      if (own != nullptr && own->displacement) t.outside = own->displacement;
      if (value > 0.0) {
        t.value = value;
      } else if (own != nullptr && own->magnitude && *own->magnitude > 0.0) {
        t.value = own->magnitude;
      } else {
        const bool material = object->GetMaterialRequirementModifier() != XCAFDimTolObjects_GeomToleranceMatReqModif_None;
        out.warnings.push_back("tolerance " + std::to_string(out.tolerances.size() + 1) + " (" + to_string(t.type) +
                               ", " + std::to_string(t.faces.size()) + " face" + (t.faces.size() == 1 ? "" : "s") +
                               "): its magnitude was not read (neither OpenCASCADE, which reads 0 where the file " +
                               "stores it in a complex entity, nor the file's own text gave one" +
                               (material ? "; or a zero zone at a material condition" : "") + ")");
      }
      if (t.value && t.outside && !(*t.outside >= 0.0 && *t.outside <= *t.value)) {
        out.warnings.push_back("tolerance " + std::to_string(out.tolerances.size() + 1) + " (" + to_string(t.type) +
                               "): its unequally disposed zone reaches " + std::to_string(*t.outside) +
                               " mm outside, beyond its " + std::to_string(*t.value) + " mm: not taken");
        t.value.reset();
        t.outside.reset();
      }
      out.tolerances.push_back(std::move(t));
    }
  } catch (const Standard_Failure& e) {
    fail(path, std::string("OpenCASCADE failed reading its PMI: ") + e.GetMessageString());
  }
  return out;
}

}  // namespace probecomp::cad
