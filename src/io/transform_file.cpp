#include "probecomp/io/transform_file.hpp"

#include <Eigen/SVD>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "probecomp/error.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::io {

namespace {

// A rotation's columns are orthonormal to rounding; a matrix typed or printed with 6+ significant digits holds
// them to about 1e-6, and a scale or shear of any consequence is far beyond it.
constexpr double kOrthonormal = 1e-6;

}  // namespace

geometry::RigidTransform read_transform(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot be opened (missing or unreadable)");
  Eigen::Matrix4d M;
  int rows = 0, number = 0, last_line = 0;
  std::string line;
  while (std::getline(in, line)) {
    ++number;
    const std::string text = trim(line);
    if (text.empty() || text.starts_with("#")) continue;
    const std::string where = name + ":" + std::to_string(number) + ": ";
    if (rows == 4) throw InputError(where + "more than four rows (a 4 x 4 matrix, CAD -> machine, is expected)");
    std::vector<double> values;
    std::size_t pos = 0;
    while (pos < text.size()) {
      while (pos < text.size() && (text[pos] == ' ' || text[pos] == '\t' || text[pos] == ',' || text[pos] == '\r')) ++pos;
      if (pos >= text.size()) break;
      std::size_t end = pos;
      while (end < text.size() && text[end] != ' ' && text[end] != '\t' && text[end] != ',' && text[end] != '\r') ++end;
      const std::string field = text.substr(pos, end - pos);
      // A leading '+' is allowed here: matrices are often printed with signs on every entry.
      const std::optional<double> v = parse_number(std::string_view(field).substr(field.starts_with("+") ? 1 : 0));
      if (!v || !std::isfinite(*v)) throw InputError(where + "'" + field + "' is not a finite number");
      values.push_back(*v);
      pos = end;
    }
    if (values.size() != 4) {
      throw InputError(where + "row " + std::to_string(rows + 1) + " has " + std::to_string(values.size()) +
                       " numbers; a 4 x 4 matrix has four per row");
    }
    for (int c = 0; c < 4; ++c) M(rows, c) = values[static_cast<std::size_t>(c)];
    ++rows;
    last_line = number;
  }
  if (rows < 4) {
    throw InputError(name + ": " + std::to_string(rows) + " rows; a 4 x 4 matrix (CAD -> machine) has four");
  }
  const std::string where = name + ":" + std::to_string(last_line) + ": ";
  if (M.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
    throw InputError(where + "the last row must be 0 0 0 1 (a rigid transform, not a projection)");
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > kOrthonormal || R.determinant() < 0.0) {
    throw InputError(name + ": the upper-left 3 x 3 is not a rotation (" +
                     (R.determinant() < 0.0 ? std::string("it mirrors") : "its columns are not orthonormal to 1e-6") +
                     "): only rigid transforms are allowed, no scaling, shear or mirroring");
  }
  geometry::RigidTransform T = geometry::RigidTransform::Identity();
  // Re-orthonormalised (nearest rotation, polar decomposition by SVD) so that rounding in the file does not scale.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

}  // namespace probecomp::io
