// read_point_csv on CSV as other software writes it (issue 20, item 8), against values written by hand.

#include "probecomp/io/point_table.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "probecomp/error.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {
namespace {

namespace fs = std::filesystem;

// Writes `bytes` to a file of its own and reads it back as a point table.
PointTable read_text(const std::string& bytes, std::optional<LengthUnit> unit = std::nullopt) {
  const fs::path p = fs::temp_directory_path() /
                     ("probecomp_point_table_" +
                      std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".csv");
  std::ofstream(p, std::ios::binary) << bytes;
  struct Remove {
    fs::path p;
    ~Remove() {
      std::error_code ec;
      fs::remove(p, ec);
    }
  } remove{p};
  return read_point_csv(p, unit);
}

TEST(ReadPointCsv, LengthsInTheDeclaredUnitAreReadInMillimetres) {
  const PointTable t = read_text("x,y,z,i,j,k,id\n1,-0.5,2,0,0,3,7\n", kInch);
  EXPECT_EQ(t.unit.name, std::string("inch"));
  EXPECT_NEAR((t.points[0] - Point3(25.4, -12.7, 50.8)).norm(), 0.0, 1e-12);
  EXPECT_EQ((*t.normals)[0], Vector3(0, 0, 1));  // normals and carried fields keep what the file says
  EXPECT_EQ(t.rows[0][6], "7");
  EXPECT_EQ(read_text("x,y,z\n1,2,3\n").unit.name, std::string("mm"));
}

TEST(ReadPointCsv, AByteOrderMarkAndCrlfLineEnds) {
  const PointTable t = read_text("\xEF\xBB\xBFx,y,z\r\n1.5,2,3\r\n4,5,6.25\r\n");
  ASSERT_EQ(t.points.size(), 2u);
  EXPECT_EQ(t.columns[0], "x");
  EXPECT_EQ(t.points[0], Point3(1.5, 2, 3));
  EXPECT_EQ(t.points[1], Point3(4, 5, 6.25));
}

TEST(ReadPointCsv, SemicolonsWithDecimalCommasAndTabs) {
  const PointTable s = read_text("X;Y;Z;label\n1,5;-2,25;3;A,1\n");
  ASSERT_EQ(s.points.size(), 1u);
  EXPECT_EQ(s.points[0], Point3(1.5, -2.25, 3));
  EXPECT_EQ(s.rows[0][3], "A,1");  // a carried field stays as written
  const PointTable t = read_text("x\ty\tz\n1.5\t2\t3\n");
  EXPECT_EQ(t.points[0], Point3(1.5, 2, 3));
}

TEST(ReadPointCsv, QuotedNamesAndFields) {
  const PointTable t = read_text("\"x\",\"y\",\"z\",\"name\"\n1,2,3,\"bolt, left \"\"A\"\"\"\n");
  ASSERT_EQ(t.columns.size(), 4u);
  EXPECT_EQ(t.columns[3], "name");
  EXPECT_EQ(t.points[0], Point3(1, 2, 3));
  EXPECT_EQ(t.rows[0][3], "bolt, left \"A\"");
  EXPECT_EQ(csv_field(t.rows[0][3]), "\"bolt, left \"\"A\"\"\"");  // written back whole
  EXPECT_EQ(csv_field("plain"), "plain");
}

TEST(ReadPointCsv, WhatItStillRefusesNamesTheLine) {
  auto message = [](const std::string& bytes) -> std::string {
    try {
      (void)read_text(bytes);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message("x,y,z\n1,2,\"3\n").find(":2: a quote is not closed"), std::string::npos);
  // With ',' between fields a decimal comma would be two fields: the count says so.
  EXPECT_NE(message("x,y,z\n1,5,2,3\n").find(":2: expected 3 fields, found 4"), std::string::npos);
  EXPECT_NE(message("x;y;z\n1,2,3;2;3\n").find("is not a number: '1,2,3'"), std::string::npos);
}

// Issue 21: a CSV states its unit in a comment before the header, as points_csv writes it.
TEST(ReadPointCsv, ALengthsCommentStatesTheUnit) {
  const PointTable t = read_text("# lengths in inch\nx,y,z,r\n1,2,3,0.5\n# lengths in mm (after the header: a comment)\n");
  EXPECT_TRUE(t.unit == kInch);
  EXPECT_EQ(t.points[0], Point3(25.4 * 1, 25.4 * 2, 25.4 * 3));
  EXPECT_EQ((*t.radii)[0], 25.4 * 0.5);
  try {
    (void)read_text("#  Lengths in furlongs\nx,y,z\n1,2,3\n");
    ADD_FAILURE() << "an unknown unit was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(".csv:1: unknown length unit 'furlongs'"), std::string::npos) << e.what();
  }
}

TEST(PointsCsv, EveryRowWithItsNumbersAsReadAndTheCarriedColumns) {
  const PointTable t = read_text("id;x;y;z;r;i;j;k\n\"a;b\";1,5;-0;1e-3;;0;0;2\n7;2;3;4;0,25;1;0;0\n");
  EXPECT_EQ(points_csv(t), "x,y,z,i,j,k,r,id\n1.5,0,0.001,0,0,2,,a;b\n2,3,4,1,0,0,0.25,7\n");
}

TEST(PointTable, DroppingTheNumbersTextKeepsTheCarriedFieldsAndLosesNoValueInMillimetres) {
  PointTable t = read_text("x,y,z,i,j,k,r,id,note\n0.1,-2.5e-3,7,0,0,3,1.5,A7,\"left, top\"\n1e2,2,3,1,0,0,0.25,,x\n");
  const std::vector<double> x = {t.points[0].x(), t.points[0].y(), t.points[1].x()};
  t.drop_number_text();
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0][0], "");
  EXPECT_EQ(t.rows[0][6], "");
  EXPECT_EQ(t.rows[0][7], "A7");
  EXPECT_EQ(t.rows[0][8], "left, top");
  EXPECT_EQ(t.rows[1][7], "");
  EXPECT_EQ(t.rows[1][8], "x");
  // An output asks row_value for a number and falls back to the table's own double, which is the file's: 0.1 is
  // the double "0.1" reads as.
  EXPECT_EQ(row_value(t, 0, 0, t.points[0].x()), 0.1);
  EXPECT_EQ(row_value(t, 1, 0, t.points[0].y()), -2.5e-3);
  EXPECT_EQ(x[2], 100.0);
  EXPECT_EQ((*t.radii)[0], 1.5);
  EXPECT_EQ(t.carried_fields(0), ",A7,\"left, top\"");
  // In inches the text is the exact value: kept.
  PointTable inch = read_text("x,y,z,id\n0.1,2,3,A\n", kInch);
  inch.drop_number_text();
  EXPECT_EQ(inch.rows[0][0], "0.1");
}

// The reader cuts the rows into blocks of 16 MB and those into pieces read in parallel: rows across both cuts, with
// comments and blank lines among them, come back in order with their own line numbers, and a bad row past the
// first block is named by its line.
TEST(PointTable, ALargeFileReadInPiecesKeepsEveryRowItsLineAndOrder) {
  constexpr int kRows = 620'000;  // about 19 MB
  std::string text = "# a scan\nx,y,z,id\n";
  std::vector<int> line(kRows);
  int number = 2;
  for (int k = 0; k < kRows; ++k) {
    if (k % 1000 == 999) {
      text += "# comment\n";
      ++number;
    }
    if (k % 777 == 0) {
      text += "\n";
      ++number;
    }
    text += std::to_string(k) + ".25," + std::to_string(-k) + ",0.5,P" + std::to_string(k) + "\r\n";
    line[static_cast<std::size_t>(k)] = ++number;
  }
  ASSERT_GT(text.size(), std::size_t{17} << 20);
  const PointTable t = read_text(text);
  ASSERT_EQ(t.points.size(), static_cast<std::size_t>(kRows));
  int wrong = 0;
  for (int k = 0; k < kRows; ++k) {
    const std::size_t i = static_cast<std::size_t>(k);
    const std::string id = std::to_string(k);
    wrong += t.points[i] != Point3(k + 0.25, -k, 0.5) || t.line[i] != line[i] || t.rows[i][3] != "P" + id;
  }
  EXPECT_EQ(wrong, 0);

  // A row past the first 16 MB with a letter in y.
  const int bad = 580'000;
  const std::string row = std::to_string(bad) + ".25," + std::to_string(-bad) + ",";
  std::string needle(1, '\n');
  needle += row;
  const std::size_t at = text.find(needle) + 1;
  std::string broken = text;
  broken[at + std::to_string(bad).size() + 4] = 'q';
  try {
    (void)read_text(broken);
    ADD_FAILURE() << "a bad row was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(".csv:" + std::to_string(line[bad]) + ": column 'y' is not a number: 'q"),
              std::string::npos)
        << e.what();
  }
}

TEST(Fields, KeepingSomeColumnsOfEqualRowsStoresOnlyThose) {
  Fields f;
  f.push_back({"1.5", "2", "a,b", "id7"});
  f.push_back({"-3", "", "", "id8"});
  const Fields kept = f.keeping({3, 2});
  ASSERT_EQ(kept.size(), 2u);
  ASSERT_EQ(kept[0].size(), 4u);
  EXPECT_EQ(kept[0][0], "");
  EXPECT_EQ(kept[0][1], "");
  EXPECT_EQ(kept[0][2], "a,b");
  EXPECT_EQ(kept[0][3], "id7");
  EXPECT_EQ(kept[1][2], "");
  EXPECT_EQ(kept[1][3], "id8");
  // Rows added later keep the same columns; one of another width cannot be.
  Fields compact = kept;
  compact.push_back(std::vector<std::string>{"x", "y", "z", "w"});
  EXPECT_EQ(compact[2][0], "");
  EXPECT_EQ(compact[2][2], "z");
  EXPECT_EQ(compact[2][3], "w");
  EXPECT_THROW(compact.push_back(std::vector<std::string>{"x", "y", "z"}), std::logic_error);
  EXPECT_THROW(compact.append(f), std::logic_error);
  // Rows of different lengths keep every field's place.
  f.push_back({"9"});
  const Fields ragged = f.keeping({0});
  ASSERT_EQ(ragged[2].size(), 1u);
  EXPECT_EQ(ragged[2][0], "9");
  EXPECT_EQ(ragged[0][0], "1.5");
  EXPECT_EQ(ragged[0][3], "");
}

TEST(Fields, RowsOfAnyLengthComeBackAsWritten) {
  Fields f;
  EXPECT_TRUE(f.empty());
  f.push_back({"1.5", "", "a,b"});
  f.push_back(std::vector<std::string>{});  // a row of no fields
  f.push_back({"x"});
  f.push_back({"", ""});
  f.shrink_to_fit();
  ASSERT_EQ(f.size(), 4u);
  ASSERT_EQ(f[0].size(), 3u);
  EXPECT_EQ(f[0][0], "1.5");
  EXPECT_EQ(f[0][1], "");
  EXPECT_EQ(f[0][2], "a,b");
  EXPECT_EQ(f[1].size(), 0u);
  ASSERT_EQ(f[2].size(), 1u);
  EXPECT_EQ(f[2][0], "x");
  ASSERT_EQ(f[3].size(), 2u);
  EXPECT_EQ(f[3][0], "");
  EXPECT_EQ(f[3][1], "");
  std::size_t rows = 0, fields = 0;
  for (const auto row : f) {
    ++rows;
    fields += row.size();
  }
  EXPECT_EQ(rows, 4u);
  EXPECT_EQ(fields, 6u);
}

}  // namespace
}  // namespace probecomp::io

TEST(PointTable, RadiusColumnGivesEachRowItsTipRadiusAndLeavesEmptyCellsToTheDefault) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / "probecomp_radius_column.csv";
  {
    std::ofstream f(p);
    f << "x,y,z,r,tip\n1,2,3,0.5,small\n4,5,6,,default\n7,8,9,1,big\n";
  }
  const probecomp::io::PointTable t = probecomp::io::read_point_csv(p);
  ASSERT_TRUE(t.radii.has_value());
  ASSERT_EQ(t.radii->size(), 3u);
  EXPECT_EQ((*t.radii)[0], 0.5);
  EXPECT_TRUE(std::isnan((*t.radii)[1]));
  EXPECT_EQ((*t.radii)[2], 1.0);
  // r is ours, not carried; tip is carried.
  EXPECT_EQ(t.carried_columns(), std::vector<int>{4});
  const probecomp::io::PointTable inch = probecomp::io::read_point_csv(p, probecomp::io::kInch);
  EXPECT_DOUBLE_EQ((*inch.radii)[0], 0.5 * 25.4);
  std::filesystem::remove(p);
}

TEST(PointTable, RadiusThatIsNotAPositiveNumberNamesTheLine) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() / "probecomp_bad_radius.csv";
  for (const char* bad : {"0", "-1", "abc", "nan"}) {
    {
      std::ofstream f(p);
      f << "x,y,z,r\n1,2,3,1\n4,5,6," << bad << "\n";
    }
    try {
      (void)probecomp::io::read_point_csv(p);
      ADD_FAILURE() << "accepted r = " << bad;
    } catch (const probecomp::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(":3:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("'r'"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove(p);
}
