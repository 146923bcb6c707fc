// The characteristics and datum frames in a compensated QIF document (results/qif_characteristics.hpp), on a block
// OpenCASCADE models: the frame A|B|C on its bottom, front and left planes is set up as measured (a coordinate system
// and its actual transform) and by datum precedence, with the primary and secondary datums' directions: the bottom's
// and the front's outward normals, (0, 0, −1) and (0, −1, 0), exactly. The document validates against the QIF 3.0
// schemas (xmllint).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <pugixml.hpp>

#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/results/files.hpp"
#include "support/prismatic_parts.hpp"

namespace probecomp::results {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = fs::temp_directory_path() / ("probecomp_qif_frames_" + name);
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

Vector3 vector_of(const char* text) {
  std::istringstream in(text);
  Vector3 v;
  in >> v.x() >> v.y() >> v.z();
  return v;
}

TEST(QifCharacteristics, AFrameOnPlanesIsSetUpByDatumPrecedenceWithItsDatumsDirections) {
  ASSERT_EQ(std::system("xmllint --version >/dev/null 2>&1"), 0) << "xmllint is missing (Debian libxml2-utils)";
  const cad::Model model = testing::block_with_hole();
  const testing::BlockWithHoleFaces f = testing::faces_of_block_with_hole(model);
  // The part exactly nominal and where the CAD puts it: grids on the four faces.
  compensation::CompensationResult result;
  std::ostringstream csv;
  csv << "x,y,z\n";
  const auto add = [&](const Point3& p, int face) {
    compensation::CompensatedPoint c;
    c.status = compensation::PointStatus::Ok;
    c.face = face;
    c.contact = p;
    c.uncertainty = 0.001;
    result.points.push_back(c);
    csv << p.x() << ',' << p.y() << ',' << p.z() << '\n';
  };
  for (double x = 5; x <= 25; x += 5) {
    for (double y = 5; y <= 35; y += 10) {
      add(Point3(x, y, 0), f.bottom);
      add(Point3(x, y, 20), f.top);
    }
    for (double z = 5; z <= 15; z += 5) add(Point3(x, 0, z), f.front);
  }
  for (double y = 5; y <= 35; y += 10) {
    for (double z = 5; z <= 15; z += 5) add(Point3(0, y, z), f.left);
  }
  inspection::Specification spec;
  spec.datums = {{"A", {f.bottom}}, {"B", {f.front}}, {"C", {f.left}}};
  spec.characteristics = {{.name = "P", .faces = {f.top}, .tolerance = 0.1, .outside = {}, .datums = {"A", "B", "C"}}};
  const inspection::Inspection judged = inspection::evaluate(spec, model, result);
  ASSERT_TRUE(judged.frames.at("A|B|C").ok()) << judged.frames.at("A|B|C").reason;

  const std::string xml =
      compensated_qif(io::read_point_csv(write("points.csv", csv.str())), result, "points.csv", &judged);
  const fs::path document = write("judged.qif", xml), log = write("xmllint.log", "");
  const std::string command = "xmllint --nonet --noout --schema '" + std::string(PROBECOMP_TEST_QIF_XSD) + "' '" +
                              document.string() + "' >'" + log.string() + "' 2>&1";
  EXPECT_EQ(std::system(command.c_str()), 0) << "does not validate: see " << log;

  pugi::xml_document doc;
  ASSERT_TRUE(doc.load_string(xml.c_str()));
  const pugi::xml_node root = doc.child("QIFDocument");
  const pugi::xml_node frame = root.child("DatumReferenceFrames").child("DatumReferenceFrame");
  ASSERT_TRUE(frame);
  EXPECT_STREQ(frame.child_value("Name"), "A|B|C");
  const pugi::xml_node system = root.child("CoordinateSystems").child("CoordinateSystemDefinitions").child("CoordinateSystem");
  ASSERT_TRUE(system);
  EXPECT_STREQ(system.child_value("Name"), "A|B|C");
  const pugi::xml_node operations = system.child("AlignmentOperations");
  ASSERT_TRUE(operations);
  EXPECT_EQ(operations.attribute("n").as_int(), 1);
  const pugi::xml_node precedence = operations.child("DatumPrecedence");
  ASSERT_TRUE(precedence);
  EXPECT_STREQ(precedence.child_value("SequenceNumber"), "1");
  EXPECT_STREQ(precedence.child_value("DatumReferenceFrameId"), frame.attribute("id").value());
  EXPECT_LT((vector_of(precedence.child_value("PrimaryAxis")) - Vector3(0, 0, -1)).norm(), 1e-12);
  EXPECT_LT((vector_of(precedence.child_value("SecondaryAxis")) - Vector3(0, -1, 0)).norm(), 1e-12);
}

}  // namespace
}  // namespace probecomp::results
