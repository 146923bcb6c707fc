#include "qif_characteristics.hpp"

#include <algorithm>
#include <functional>
#include <initializer_list>
#include <map>
#include <sstream>
#include <stdexcept>

#include <pugixml.hpp>

#include "probecomp/io/format.hpp"

namespace probecomp::results {

namespace {

// The first child of `parent` named one of `names`; null when none is there.
pugi::xml_node first_of(pugi::xml_node parent, std::initializer_list<const char*> names) {
  for (pugi::xml_node c : parent.children()) {
    for (const char* n : names) {
      if (std::string(c.name()) == n) return c;
    }
  }
  return {};
}

// `name` inserted where QIF's sequence puts it: before the first of `after_it` present, else at the end.
pugi::xml_node insert(pugi::xml_node parent, const char* name, std::initializer_list<const char*> after_it) {
  const pugi::xml_node before = first_of(parent, after_it);
  return before ? parent.insert_child_before(name, before) : parent.append_child(name);
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

// The sections that follow `name` in QIFDocument's sequence (QIFDocument.xsd), for insert().
constexpr std::initializer_list<const char*> kAfterDatumDefinitions = {
    "DatumTargetDefinitions", "Transforms", "CoordinateSystems", "DatumReferenceFrames", "MeasurementResources",
    "ThreadSpecifications", "Product", "Features", "FeatureZones", "Characteristics", "Plan", "Results", "Statistics",
    "ManufacturingProcessTraceabilities", "Rules", "UserDataXML", "Signature"};
constexpr std::initializer_list<const char*> kAfterDatumReferenceFrames = {
    "MeasurementResources", "ThreadSpecifications", "Product", "Features", "FeatureZones", "Characteristics", "Plan",
    "Results", "Statistics", "ManufacturingProcessTraceabilities", "Rules", "UserDataXML", "Signature"};

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

  pugi::xml_node definitions = insert(root, "DatumDefinitions", kAfterDatumDefinitions);
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

  pugi::xml_node frames = insert(root, "DatumReferenceFrames", kAfterDatumReferenceFrames);
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
void add_actual_frames(pugi::xml_node root, pugi::xml_node results, const inspection::Inspection& inspection,
                       const std::function<std::string()>& next, const std::function<std::string(double)>& length) {
  std::vector<std::pair<const std::string*, const inspection::DatumFrame*>> located;
  for (const auto& [key, frame] : inspection.frames) {
    if (!key.empty() && frame.ok()) located.emplace_back(&key, &frame);
  }
  if (located.empty()) return;
  std::initializer_list<const char*> after_systems = {
      "DatumReferenceFrames", "MeasurementResources", "ThreadSpecifications", "Product", "Features", "FeatureZones",
      "Characteristics", "Plan", "Results", "Statistics", "ManufacturingProcessTraceabilities", "Rules", "UserDataXML",
      "Signature"};
  pugi::xml_node systems = insert(root, "CoordinateSystems", after_systems).append_child("CoordinateSystemDefinitions");
  pugi::xml_node transforms = insert(results, "ActualTransforms", {"CoordinateSystemActualTransformAssociations",
                                                                   "InspectionStatus", "ActualComponentIds"});
  pugi::xml_node associations = insert(results, "CoordinateSystemActualTransformAssociations",
                                       {"InspectionStatus", "ActualComponentIds"});
  const auto vector = [](const Vector3& v) {
    return io::fixed(v.x(), 12) + " " + io::fixed(v.y(), 12) + " " + io::fixed(v.z(), 12);
  };
  for (const auto& [key, frame] : located) {
    const std::string system_id = next(), transform_id = next();
    pugi::xml_node system = systems.append_child("CoordinateSystem");
    system.append_attribute("id") = system_id.c_str();
    text(system, "Name", *key);

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
    standards = insert(root, "StandardsDefinitions", {"SoftwareDefinitions", "AlgorithmDefinitions",
                                                      "PreInspectionTraceability", "FileUnits", "DatumDefinitions",
                                                      "DatumTargetDefinitions", "Transforms", "CoordinateSystems",
                                                      "DatumReferenceFrames", "MeasurementResources",
                                                      "ThreadSpecifications", "Product", "Features", "FeatureZones",
                                                      "Characteristics", "Plan", "Results", "Statistics",
                                                      "ManufacturingProcessTraceabilities", "Rules", "UserDataXML",
                                                      "Signature"});
    standards.append_attribute("n") = 0;
  }
  const std::string standard_id = next();
  pugi::xml_node standard = standards.append_child("Standard");
  standard.append_attribute("id") = standard_id.c_str();
  standard.append_child("Organization").append_child("StandardsOrganizationEnum").text().set("ISO");
  text(standard, "Designator", "1101");
  standards.attribute("n").set_value(standards.attribute("n").as_int() + 1);

  const std::map<std::string, std::string> frame_ids = add_datum_frames(root, inspection, next);

  pugi::xml_node characteristics = insert(root, "Characteristics", {"Plan", "Results", "Statistics",
                                                                    "ManufacturingProcessTraceabilities", "Rules",
                                                                    "UserDataXML", "Signature"});
  text(characteristics, "FormalStandardId", standard_id);
  pugi::xml_node definitions = characteristics.append_child("CharacteristicDefinitions");
  pugi::xml_node nominals = characteristics.append_child("CharacteristicNominals");
  pugi::xml_node items = characteristics.append_child("CharacteristicItems");
  const int n = static_cast<int>(inspection.characteristics.size());
  for (pugi::xml_node list : {definitions, nominals, items}) list.append_attribute("n") = n;

  // In the first MeasurementResults: what was measured of each.
  pugi::xml_node results = root.child("Results").child("MeasurementResultsSet").child("MeasurementResults");
  if (!results) throw std::logic_error("the QIF document written has no MeasurementResults");
  pugi::xml_node measured = insert(results, "MeasuredCharacteristics", {"ActualTransforms",
                                                                        "CoordinateSystemActualTransformAssociations",
                                                                        "InspectionStatus", "ActualComponentIds"})
                                .append_child("CharacteristicMeasurements");
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
                   {"probecomp:reason", evaluated ? std::string() : c.reason}});
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
  add_actual_frames(root, results, inspection, next, length);
  root.attribute("idMax").set_value(static_cast<long long>(id));
  std::ostringstream out;
  doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  xml = out.str();
}

}  // namespace probecomp::results
