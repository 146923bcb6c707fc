#include "measurement_program.hpp"

#include <sstream>

#include "probecomp/io/format.hpp"

namespace probecomp::cli {

std::string dmis_measurement_program(const std::string& title, const std::vector<ProgrammedTouch>& touches,
                                     const std::vector<std::string>& comments) {
  std::ostringstream out;
  out << "DMISMN/'" << title << "',05.3\nUNITS/MM,ANGDEC\n";
  for (const std::string& c : comments) out << "$$ " << c << "\n";
  for (const ProgrammedTouch& t : touches) {
    const std::string xyz = io::mm(t.point.x()) + "," + io::mm(t.point.y()) + "," + io::mm(t.point.z()) + "," +
                            io::unit(t.normal.x()) + "," + io::unit(t.normal.y()) + "," + io::unit(t.normal.z());
    out << "F(" << t.label << ")=FEAT/POINT,CART," << xyz << "\n";
    out << "MEAS/POINT,F(" << t.label << "),1\n";
    out << "PTMEAS/CART," << xyz << "\n";
    out << "ENDMES\n";
  }
  out << "ENDFIL\n";
  return out.str();
}

}  // namespace probecomp::cli
