// OutputFiles and check_outputs_spare_inputs on real files in a scratch directory.

#include "probecomp/io/output_files.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "probecomp/error.hpp"

namespace probecomp::io {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Scratch {
  fs::path dir;
  // One directory per test (ctest runs tests in parallel).
  Scratch()
      : dir(fs::temp_directory_path() /
            ("probecomp_output_files_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

TEST(OutputFiles, NothingReachesADestinationUntilCommit) {
  const Scratch s;
  {
    OutputFiles files;
    files.add(s.dir / "a.csv", "new a");
    EXPECT_FALSE(fs::exists(s.dir / "a.csv"));
    files.commit();
  }
  EXPECT_EQ(read(s.dir / "a.csv"), "new a");
  EXPECT_FALSE(fs::exists(s.dir / "a.partial.csv"));
}

TEST(OutputFiles, AFailureLeavesTheDestinationsAsTheyWereAndNoTemporaries) {
  const Scratch s;
  std::ofstream(s.dir / "a.csv") << "old a";
  try {
    OutputFiles files;
    files.add(s.dir / "a.csv", "new a");
    files.add(s.dir / "missing_dir" / "b.json", "b");  // cannot be written
    files.commit();
    FAIL() << "the second file cannot be written";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("b.json"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read(s.dir / "a.csv"), "old a");
  EXPECT_EQ(std::distance(fs::directory_iterator(s.dir), fs::directory_iterator()), 1);  // a.csv alone
}

TEST(OutputFiles, AWriterThrowingLeavesNothing) {
  const Scratch s;
  try {
    OutputFiles files;
    files.add(s.dir / "surfaces.igs", [](const fs::path& temporary) {
      EXPECT_EQ(temporary.extension(), ".igs");  // writers that choose the format by it still can
      std::ofstream(temporary) << "half";
      throw CadError("the writer failed");
    });
    files.commit();
  } catch (const CadError&) {
  }
  EXPECT_TRUE(fs::is_empty(s.dir));
}

TEST(CheckOutputsSpareInputs, AnOutputNamingAnInputByAnyPathIsRefused) {
  const Scratch s;
  std::ofstream(s.dir / "raw.csv") << "x,y,z\n";
  fs::create_symlink(s.dir / "raw.csv", s.dir / "link.csv");
  const std::vector<NamedPath> inputs = {{"--points", s.dir / "raw.csv"}, {"--cad", s.dir / "part.stp"}};
  for (const fs::path& out : {s.dir / "raw.csv", s.dir / "." / "raw.csv", s.dir / "sub" / ".." / "raw.csv",
                              s.dir / "link.csv", s.dir / "part.stp"}) {
    EXPECT_THROW(check_outputs_spare_inputs({{"--output", out}}, inputs), std::invalid_argument) << out;
  }
  EXPECT_NO_THROW(check_outputs_spare_inputs({{"--output", s.dir / "out.csv"}, {"--json", ""}}, inputs));
  EXPECT_THROW(check_outputs_spare_inputs({{"--output", s.dir / "o.csv"}, {"--json", s.dir / "o.csv"}}, inputs),
               std::invalid_argument);
}

}  // namespace
}  // namespace probecomp::io
