// probecomp convert: point files between CSV, DMIS and QIF, units, radii and carried columns kept, every number
// exactly as read (from the rows' text: nothing is rescaled or rounded).

#include <filesystem>
#include <stdexcept>

#include "cli/commands.hpp"
#include "probecomp/io/dmis.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/io/qif.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::cli {

int run_convert(const ConvertArgs& a) {
  const std::string out = io::lower(std::filesystem::path(a.output).extension().string());
  const bool csv = out == ".csv", dmis = io::is_dmis(a.output), qif = io::is_qif(a.output);
  if (!csv && !dmis && !qif) throw std::invalid_argument("OUT must end in .csv, .dmo (DMIS) or .qif, not '" + out + "'");
  io::check_outputs_spare_inputs({{"OUT", a.output}}, {{"IN", a.input}});
  std::optional<io::LengthUnit> declared;
  if (!a.units.empty()) declared = io::length_unit(a.units);
  const io::PointTable table = io::read_points(a.input, declared);
  const std::string text = csv ? io::points_csv(table) : dmis ? io::points_dmis(table, a.input) : io::points_qif(table);
  io::OutputFiles files;
  files.add(a.output, text);
  files.commit();
  return 0;
}

}  // namespace probecomp::cli
