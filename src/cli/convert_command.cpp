// probecomp convert: point files between CSV, DMIS and QIF, units, radii and carried columns kept, every number
// exactly as read (from the rows' text: nothing is rescaled or rounded).

#include <filesystem>
#include <stdexcept>

#include "cli/commands.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::cli {

int run_convert(const ConvertArgs& a) {
  const std::optional<io::PointFormat> format = io::written_point_format(a.output);
  if (!format) {
    throw std::invalid_argument("OUT must end in .csv, .dmo (DMIS) or .qif, not '" +
                                io::lower(std::filesystem::path(a.output).extension().string()) + "'");
  }
  io::check_outputs_spare_inputs({{"OUT", a.output}}, {{"IN", a.input}});
  std::optional<io::LengthUnit> declared;
  if (!a.units.empty()) declared = io::length_unit(a.units);
  const io::PointTable table = io::read_points(a.input, declared);
  const std::string text = io::points_text(table, *format, a.input);
  io::OutputFiles files;
  files.add(a.output, text);
  files.commit();
  return 0;
}

}  // namespace probecomp::cli
