#include "qif_characteristics.hpp"

#include <initializer_list>
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
    attributes(d, {{"probecomp:faces", faces}, {"probecomp:datums", frame}});
    text(d, "Name", c.spec.name);
    text(d, "ToleranceValue", length(c.spec.tolerance));
    text(d, "OuterDisposition", length(c.outside));

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
  root.attribute("idMax").set_value(static_cast<long long>(id));
  std::ostringstream out;
  doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  xml = out.str();
}

}  // namespace probecomp::results
