#include "probecomp/io/point_files.hpp"

#include "probecomp/io/dmis.hpp"
#include "probecomp/io/qif.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {

PointFormat point_format(const std::filesystem::path& path) {
  if (is_dmis(path)) return PointFormat::Dmis;
  if (is_qif(path)) return PointFormat::Qif;
  return PointFormat::Csv;
}

std::optional<PointFormat> written_point_format(const std::filesystem::path& path) {
  const PointFormat f = point_format(path);
  if (f == PointFormat::Csv && lower(path.extension().string()) != ".csv") return std::nullopt;
  return f;
}

PointTable read_points(const std::filesystem::path& path, std::optional<LengthUnit> declared,
                       const FileProgress& progress, NumberText number_text) {
  PointTable t;
  switch (point_format(path)) {
    case PointFormat::Dmis: t = read_point_dmis(path, declared); break;
    case PointFormat::Qif: t = read_point_qif(path, declared); break;
    case PointFormat::Csv: return read_point_csv(path, declared, progress, number_text);
  }
  if (number_text == NumberText::Drop) t.drop_number_text();
  return t;
}

std::string points_text(const PointTable& table, PointFormat format, const std::string& source) {
  switch (format) {
    case PointFormat::Dmis: return points_dmis(table, source);
    case PointFormat::Qif: return points_qif(table);
    case PointFormat::Csv: break;
  }
  return points_csv(table);
}

}  // namespace probecomp::io
