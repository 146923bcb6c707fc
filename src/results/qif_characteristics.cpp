#include "qif_characteristics.hpp"

#include <algorithm>
#include <array>
#include <functional>
#include <initializer_list>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <pugixml.hpp>

#include "probecomp/io/format.hpp"

namespace probecomp::results {

namespace {

// QIFDocument's sections in the order of its sequence (QIFDocument.xsd), and a MeasurementResults' (QIFResults.xsd),
// from those this file adds on.
constexpr std::array kDocumentSections = {
    "StandardsDefinitions", "SoftwareDefinitions", "AlgorithmDefinitions", "PreInspectionTraceability", "FileUnits",
    "DatumDefinitions", "DatumTargetDefinitions", "Transforms", "CoordinateSystems", "DatumReferenceFrames",
    "MeasurementResources", "ThreadSpecifications", "Product", "Features", "FeatureZones", "Characteristics", "Plan",
    "Results", "Statistics", "ManufacturingProcessTraceabilities", "Rules", "UserDataXML", "Signature"};
constexpr std::array kMeasurementResultsSections = {"MeasuredCharacteristics", "ActualTransforms",
                                                    "CoordinateSystemActualTransformAssociations", "InspectionStatus",
                                                    "ActualComponentIds"};

// `name`, one of `order`, inserted where that sequence puts it: before the first section after it that `parent`
// has, else at the end.
template <std::size_t N>
pugi::xml_node insert(pugi::xml_node parent, const char* name, const std::array<const char*, N>& order) {
  const auto at = std::find_if(order.begin(), order.end(), [&](const char* n) { return std::string_view(n) == name; });
  if (at == order.end()) throw std::logic_error(std::string("QIF section ") + name + " is not in its parent's sequence");
  for (pugi::xml_node c : parent.children()) {
    if (std::find_if(at + 1, order.end(), [&](const char* n) { return std::string_view(n) == c.name(); }) != order.end()) {
      return parent.insert_child_before(name, c);
    }
  }
  return parent.append_child(name);
}

void text(pugi::xml_node parent, const char* name, const std::string& value) {
  parent.append_child(name).text().set(value.c_str());
}

void attributes(pugi::xml_node parent, std::initializer_list<std::pair<const char*, std::string>> values) {
  pugi::xml_node a = parent.append_child("Attributes");
  int n = 0;
  for (const auto& [name, value] : values) {
    if (value.empty()) continue;
    pugi::xml_node s = a.append_child("AttributeStr");
    s.append_attribute("name") = name;
    s.append_attribute("value") = value.c_str();
    ++n;
  }
  a.prepend_attribute("n") = n;
}

const char* status(inspection::Decision d) {
  switch (d) {
    case inspection::Decision::Conforms: return "PASS";
    case inspection::Decision::DoesNotConform: return "FAIL";
    case inspection::Decision::Indeterminate: return "INDETERMINATE";
    case inspection::Decision::NotEvaluated: return "NOT_ANALYZED";
  }
  return "NOT_ANALYZED";
}

const char* precedence(std::size_t k) {
  static constexpr const char* kOrder[] = {"PRIMARY", "SECONDARY", "TERTIARY", "QUATERNARY", "QUINARY", "SENARY"};
  return kOrder[std::min<std::size_t>(k, 5)];
}

// The datums the characteristics refer to (DatumDefinitions, one per label) and their datum reference frames
// (DatumReferenceFrames, one per sequence of labels: "A|B|C"), with each datum's substitute feature as fitted (least
// squares, or tangent: ONESIDED) where a frame was set up with it. Returns each frame's id by its key.
std::map<std::string, std::string> add_datum_frames(pugi::xml_node root, const inspection::Inspection& inspection,
                                                    const std::function<std::string()>& next) {
  std::map<std::string, std::string> frame_ids;
  std::map<std::string, std::string> datum_ids;
  std::map<std::string, const inspection::DatumResult*> fitted;
  for (const inspection::FrameDatum& d : inspection.datums) fitted.try_emplace(d.datum.name, &d.datum);
  std::vector<const inspection::CharacteristicSpec*> framed;
  for (const inspection::CharacteristicResult& c : inspection.characteristics) {
    if (!c.spec.datums.empty()) framed.push_back(&c.spec);
  }
  if (framed.empty()) return frame_ids;

  pugi::xml_node definitions = insert(root, "DatumDefinitions", kDocumentSections);
  for (const inspection::CharacteristicSpec* c : framed) {
    for (const std::string& label : c->datums) {
      if (datum_ids.contains(label)) continue;
      const std::string id = next();
      datum_ids[label] = id;
      pugi::xml_node d = definitions.append_child("DatumDefinition");
      d.append_attribute("id") = id.c_str();
      if (const auto f = fitted.find(label); f != fitted.end()) {
        std::string faces;
        for (int face : f->second->faces) faces.append(faces.empty() ? "" : " ").append(std::to_string(face));
        attributes(d, {{"probecomp:faces", faces}});
      }
      text(d, "DatumLabel", label);
    }
  }
  definitions.prepend_attribute("n") = static_cast<int>(datum_ids.size());

  pugi::xml_node frames = insert(root, "DatumReferenceFrames", kDocumentSections);
  for (const inspection::CharacteristicSpec* c : framed) {
    std::string key;
    for (const std::string& d : c->datums) key.append(key.empty() ? "" : "|").append(d);
    if (frame_ids.contains(key)) continue;
    const std::string id = next();
    frame_ids[key] = id;
    pugi::xml_node frame = frames.append_child("DatumReferenceFrame");
    frame.append_attribute("id") = id.c_str();
    pugi::xml_node datums = frame.append_child("Datums");
    datums.append_attribute("n") = static_cast<int>(c->datums.size());
    for (std::size_t k = 0; k < c->datums.size(); ++k) {
      pugi::xml_node simple = datums.append_child("Datum").append_child("SimpleDatum");
      text(simple, "DatumDefinitionId", datum_ids.at(c->datums[k]));
      text(simple, "MaterialModifier", "NONE");  // regardless of feature size: the only one evaluated
      text(simple, "ReferencedComponent", "NOMINAL");
      if (const auto f = fitted.find(c->datums[k]); f != fitted.end()) {
        text(simple.append_child("SubstituteFeatureAlgorithm"), "SubstituteFeatureAlgorithmEnum",
             f->second->fit == inspection::DatumFit::Tangent ? "ONESIDED" : "LEASTSQUARES");
      }
      simple.parent().append_child("Precedence").append_child("PrecedenceEnum").text().set(precedence(k));
    }
    text(frame, "Name", key);
  }
  frames.prepend_attribute("n") = static_cast<int>(frame_ids.size());
  return frame_ids;
}

// Each datum reference frame set up, as measured: a coordinate system named after it (CoordinateSystems) and, in
// `results`, its actual transform (ActualTransforms), the two tied by a CoordinateSystemActualTransformAssociation.
// The transform takes coordinates in the frame (the nominal's, the part located by its datums) to the document's
// measured ones: X = R·x + O (TransformMatrixType), R's columns the XDirection, YDirection and ZDirection.
//
// How each was set up is its AlignmentOperations: a DatumPrecedence on its datum reference frame (`frame_ids`), with
// the primary datum's direction and the secondary's square to it, in the nominal's coordinates. Written where the
// primary has one (DatumResult::axis: a plane, cylinder or cone), which QIF requires.
void add_actual_frames(pugi::xml_node root, pugi::xml_node results, const inspection::Inspection& inspection,
                       const std::map<std::string, std::string>& frame_ids, const std::function<std::string()>& next,
                       const std::function<std::string(double)>& length) {
  std::vector<std::pair<const std::string*, const inspection::DatumFrame*>> located;
  for (const auto& [key, frame] : inspection.frames) {
    if (!key.empty() && frame.ok()) located.emplace_back(&key, &frame);
  }
  if (located.empty()) return;
  pugi::xml_node systems = insert(root, "CoordinateSystems", kDocumentSections).append_child("CoordinateSystemDefinitions");
  pugi::xml_node transforms = insert(results, "ActualTransforms", kMeasurementResultsSections);
  pugi::xml_node associations = insert(results, "CoordinateSystemActualTransformAssociations", kMeasurementResultsSections);
  const auto vector = [](const Vector3& v) {
    return io::fixed(v.x(), 12) + " " + io::fixed(v.y(), 12) + " " + io::fixed(v.z(), 12);
  };
  for (const auto& [key, frame] : located) {
    const std::string system_id = next(), transform_id = next();
    pugi::xml_node system = systems.append_child("CoordinateSystem");
    system.append_attribute("id") = system_id.c_str();
    text(system, "Name", *key);
    const auto drf = frame_ids.find(*key);
    if (drf != frame_ids.end() && !frame->datums.empty() && frame->datums.front().axis) {
      pugi::xml_node operations = system.append_child("AlignmentOperations");
      operations.append_attribute("n") = 1;
      pugi::xml_node precedence = operations.append_child("DatumPrecedence");
      text(precedence, "SequenceNumber", "1");
      text(precedence, "DatumReferenceFrameId", drf->second);
      const Vector3 primary = *frame->datums.front().axis;
      text(precedence, "PrimaryAxis", vector(primary));
      if (frame->datums.size() > 1 && frame->datums[1].axis) {
        // Square to the primary; none where it lies along it (a hole's axis under a primary plane, 1e-3 rad and
        // less: what is left would be mostly rounding), its location then setting the direction.
        const Vector3 secondary = *frame->datums[1].axis - frame->datums[1].axis->dot(primary) * primary;
        if (secondary.norm() > 1e-3) text(precedence, "SecondaryAxis", vector(secondary.normalized()));
      }
    }

    pugi::xml_node t = transforms.append_child("Transform");
    t.append_attribute("id") = transform_id.c_str();
    pugi::xml_node rotation = t.append_child("Rotation");
    const Eigen::Matrix3d R = frame->transform.linear();
    text(rotation, "XDirection", vector(R.col(0)));
    text(rotation, "YDirection", vector(R.col(1)));
    text(rotation, "ZDirection", vector(R.col(2)));
    const Vector3 o = frame->transform.translation();
    text(t, "Origin", length(o.x()) + " " + length(o.y()) + " " + length(o.z()));
    attributes(t, {{"probecomp:fixed", std::to_string(frame->fixed())}});
    text(t, "Name", *key);

    pugi::xml_node a = associations.append_child("CoordinateSystemActualTransformAssociation");
    text(a, "ActualTransformId", transform_id);
    text(a, "CoordinateSystemId", system_id);
  }
  const int n = static_cast<int>(located.size());
  systems.prepend_attribute("n") = n;
  transforms.prepend_attribute("n") = n;
  associations.prepend_attribute("n") = n;
}

}  // namespace

void add_characteristics(std::string& xml, const inspection::Inspection& inspection, double scale) {
  if (inspection.characteristics.empty()) return;
  pugi::xml_document doc;
  if (!doc.load_string(xml.c_str(), pugi::parse_default | pugi::parse_declaration)) {
    throw std::logic_error("the QIF document written is not XML");
  }
  pugi::xml_node root = doc.child("QIFDocument");
  if (root.child("Characteristics")) throw std::logic_error("the QIF document written has Characteristics already");
  long id = root.attribute("idMax").as_llong();
  const auto next = [&] { return std::to_string(++id); };
  const auto length = [&](double mm) { return io::fixed(scale * mm, 9); };

  // ISO 1101 (geometrical tolerancing) as the formal standard the characteristics are stated against.
  pugi::xml_node standards = root.child("StandardsDefinitions");
  if (!standards) {
    standards = insert(root, "StandardsDefinitions", kDocumentSections);
    standards.append_attribute("n") = 0;
  }
  const std::string standard_id = next();
  pugi::xml_node standard = standards.append_child("Standard");
  standard.append_attribute("id") = standard_id.c_str();
  standard.append_child("Organization").append_child("StandardsOrganizationEnum").text().set("ISO");
  text(standard, "Designator", "1101");
  standards.attribute("n").set_value(standards.attribute("n").as_int() + 1);

  const std::map<std::string, std::string> frame_ids = add_datum_frames(root, inspection, next);

  pugi::xml_node characteristics = insert(root, "Characteristics", kDocumentSections);
  text(characteristics, "FormalStandardId", standard_id);
  pugi::xml_node definitions = characteristics.append_child("CharacteristicDefinitions");
  pugi::xml_node nominals = characteristics.append_child("CharacteristicNominals");
  pugi::xml_node items = characteristics.append_child("CharacteristicItems");
  const int n = static_cast<int>(inspection.characteristics.size());
  for (pugi::xml_node list : {definitions, nominals, items}) list.append_attribute("n") = n;

  // In the first MeasurementResults: what was measured of each.
  pugi::xml_node results = root.child("Results").child("MeasurementResultsSet").child("MeasurementResults");
  if (!results) throw std::logic_error("the QIF document written has no MeasurementResults");
  pugi::xml_node measured =
      insert(results, "MeasuredCharacteristics", kMeasurementResultsSections).append_child("CharacteristicMeasurements");
  measured.append_attribute("n") = n;

  for (const inspection::CharacteristicResult& c : inspection.characteristics) {
    std::string frame;
    for (const std::string& d : c.spec.datums) frame.append(frame.empty() ? "" : "|").append(d);
    std::string faces;
    for (int f : c.spec.faces) faces.append(faces.empty() ? "" : " ").append(std::to_string(f));
    const std::string definition_id = next(), nominal_id = next(), item_id = next(), measurement_id = next();

    pugi::xml_node d = definitions.append_child("SurfaceProfileCharacteristicDefinition");
    d.append_attribute("id") = definition_id.c_str();
    attributes(d, {{"probecomp:faces", faces}});
    text(d, "Name", c.spec.name);
    text(d, "ToleranceValue", length(c.spec.tolerance));
    text(d, "OuterDisposition", length(c.outside));
    if (!frame.empty()) text(d, "DatumReferenceFrameId", frame_ids.at(frame));

    pugi::xml_node nominal = nominals.append_child("SurfaceProfileCharacteristicNominal");
    nominal.append_attribute("id") = nominal_id.c_str();
    text(nominal, "CharacteristicDefinitionId", definition_id);
    text(nominal, "Name", c.spec.name);

    pugi::xml_node item = items.append_child("SurfaceProfileCharacteristicItem");
    item.append_attribute("id") = item_id.c_str();
    text(item, "Name", c.spec.name);
    text(item, "CharacteristicNominalId", nominal_id);

    pugi::xml_node m = measured.append_child("SurfaceProfileCharacteristicMeasurement");
    m.append_attribute("id") = measurement_id.c_str();
    const bool evaluated = c.decision != inspection::Decision::NotEvaluated;
    attributes(m, {{"probecomp:points", std::to_string(c.points)},
                   {"probecomp:k", evaluated ? io::fixed(c.coverage, 3) : std::string()},
                   {"probecomp:reason", c.reason}});
    m.append_child("Status").append_child("CharacteristicStatusEnum").text().set(status(c.decision));
    text(m, "CharacteristicItemId", item_id);
    if (evaluated) {
      pugi::xml_node value = m.append_child("Value");
      value.append_attribute("combinedUncertainty") = length(c.u).c_str();
      value.text().set(length(c.value).c_str());
      text(m, "MaxValue", length(c.max));
      text(m, "MinValue", length(c.min));
    }
  }
  add_actual_frames(root, results, inspection, frame_ids, next, length);
  root.attribute("idMax").set_value(static_cast<long long>(id));
  std::ostringstream out;
  doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  xml = out.str();
}

}  // namespace probecomp::results
