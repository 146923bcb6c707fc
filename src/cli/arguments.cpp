#include "cli/arguments.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "probecomp/io/format.hpp"
#include "probecomp/io/text.hpp"

namespace probecomp::cli {

namespace {

// Comma-separated finite numbers; throws with `what` (the expected form) on anything else.
std::vector<double> numbers(const std::string& text, const std::string& what) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const std::string t = io::trim(item);
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(t, &used);
    } catch (const std::logic_error&) {
      used = 0;
    }
    if (t.empty() || used != t.size() || !std::isfinite(v)) {
      throw std::invalid_argument(what + ": '" + item + "' is not a number");
    }
    out.push_back(v);
  }
  if (!text.empty() && text.back() == ',') throw std::invalid_argument(what + ": trailing comma");
  return out;
}

}  // namespace

void check_probe_radius(double r) {
  if (!(r > 0.0) || !std::isfinite(r)) {
    throw std::invalid_argument("--probe-radius must be a positive, finite length, not " + fmt("%g", r));
  }
}

std::vector<int> parse_face_list(const std::string& list) {
  std::vector<int> faces;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      const auto dash = item.find('-', 1);
      std::size_t used = 0;
      if (dash == std::string::npos) {
        faces.push_back(std::stoi(item, &used));
        if (used != item.size()) throw std::invalid_argument(item);
      } else {
        const int a = std::stoi(item.substr(0, dash));
        const int b = std::stoi(item.substr(dash + 1), &used);
        if (used != item.size() - dash - 1 || b < a) throw std::invalid_argument(item);
        for (int f = a; f <= b; ++f) faces.push_back(f);
      }
    } catch (const std::logic_error&) {
      throw std::invalid_argument("--faces: '" + item + "' is not a face index or range like 3-7");
    }
  }
  return faces;
}

geometry::RigidTransform parse_misalignment(const std::string& spec) {
  const std::string what = "--misalign (tx,ty,tz,rx,ry,rz in mm and degrees)";
  const std::vector<double> v = numbers(spec, what);
  if (v.size() != 6) throw std::invalid_argument(what + ": needs 6 numbers, got " + std::to_string(v.size()));
  return geometry::from_pose({.rx = v[3], .ry = v[4], .rz = v[5], .t = Vector3(v[0], v[1], v[2])});
}

void add_deformation(const std::string& spec, simulation::Deformation& d) {
  const auto colon = spec.find(':');
  const std::string kind = io::lower(io::trim(spec.substr(0, colon)));
  const std::string args = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "bump") {
    const std::string what = "--deform bump:X,Y,Z,A,W";
    const std::vector<double> v = numbers(args, what);
    if (v.size() != 5) throw std::invalid_argument(what + ": needs 5 numbers, got " + std::to_string(v.size()));
    if (!(v[4] > 0.0)) throw std::invalid_argument(what + ": the width W must be positive");
    d.bumps.push_back({.centre = Point3(v[0], v[1], v[2]), .amplitude = v[3], .width = v[4]});
    return;
  }
  if (kind == "sine" || kind == "sinusoid") {
    const std::string what = "--deform sine:A,L,DX,DY,DZ[,OX,OY,OZ[,W[,PHASE[,BX,BY,BZ]]]]";
    const std::vector<double> v = numbers(args, what);
    if (v.size() != 5 && v.size() != 8 && v.size() != 9 && v.size() != 10 && v.size() != 13) {
      throw std::invalid_argument(what + ": needs 5, 8, 9, 10 or 13 numbers, got " + std::to_string(v.size()));
    }
    const Vector3 direction(v[2], v[3], v[4]);
    if (!(v[1] > 0.0)) throw std::invalid_argument(what + ": the wavelength L must be positive");
    if (!(direction.norm() > 0.0)) throw std::invalid_argument(what + ": the direction must not be zero");
    simulation::Sinusoid s{.amplitude = v[0], .wavelength = v[1], .direction = direction.normalized()};
    if (v.size() >= 8) s.origin = Point3(v[5], v[6], v[7]);
    if (v.size() >= 9) {
      if (v[8] < 0.0) throw std::invalid_argument(what + ": the window W must not be negative");
      s.window = v[8];
    }
    if (v.size() >= 10) s.phase = v[9];
    if (v.size() == 13) {
      const Vector3 band(v[10], v[11], v[12]);
      if (!(band.norm() > 0.0)) throw std::invalid_argument(what + ": the band direction must not be zero");
      if (!(s.window > 0.0)) throw std::invalid_argument(what + ": a band needs a window W > 0");
      s.band = band.normalized();
    }
    d.sinusoids.push_back(s);
    return;
  }
  if (kind == "crease") {
    const std::string what = "--deform crease:OX,OY,OZ,DX,DY,DZ,H,W";
    const std::vector<double> v = numbers(args, what);
    if (v.size() != 8) throw std::invalid_argument(what + ": needs 8 numbers, got " + std::to_string(v.size()));
    const Vector3 direction(v[3], v[4], v[5]);
    if (!(direction.norm() > 0.0)) throw std::invalid_argument(what + ": the direction must not be zero");
    if (!(v[7] > 0.0)) throw std::invalid_argument(what + ": the width W must be positive");
    d.creases.push_back({.origin = Point3(v[0], v[1], v[2]), .direction = direction.normalized(), .height = v[6],
                         .width = v[7]});
    return;
  }
  if (kind == "twist") {
    const std::string what = "--deform twist:OX,OY,OZ,D1X,D1Y,D1Z,D2X,D2Y,D2Z,A,L";
    const std::vector<double> v = numbers(args, what);
    if (v.size() != 11) throw std::invalid_argument(what + ": needs 11 numbers, got " + std::to_string(v.size()));
    const Vector3 first(v[3], v[4], v[5]), second(v[6], v[7], v[8]);
    if (!(first.norm() > 0.0) || !(second.norm() > 0.0)) {
      throw std::invalid_argument(what + ": the directions must not be zero");
    }
    if (!(v[10] > 0.0)) throw std::invalid_argument(what + ": the length L must be positive");
    d.twists.push_back({.origin = Point3(v[0], v[1], v[2]), .first = first.normalized(), .second = second.normalized(),
                        .amplitude = v[9], .length = v[10]});
    return;
  }
  throw std::invalid_argument("--deform: '" + spec +
                              "' is none of bump:X,Y,Z,A,W, sine:A,L,DX,DY,DZ[,...], crease:... or twist:...");
}

simulation::Pretravel parse_pretravel(const std::string& spec) {
  const std::string what = "--pretravel P0,B,A[,N[,PHASE]] (mm, mm, mm, lobes, degrees)";
  const std::vector<double> v = numbers(spec, what);
  if (v.size() < 3 || v.size() > 5) {
    throw std::invalid_argument(what + ": needs 3 to 5 numbers, got " + std::to_string(v.size()));
  }
  simulation::Pretravel p{.constant = v[0], .axial = v[1], .lobes = v[2]};
  if (v.size() >= 4) {
    // Lobes about the stylus come whole: a kinematic seat has 3, some strain-gauge probes 4 or 6.
    if (!(v[3] >= 1.0 && v[3] <= 1000.0) || v[3] != std::floor(v[3])) {
      throw std::invalid_argument(what + ": the lobe count N must be a positive whole number, not " + fmt("%g", v[3]));
    }
    p.lobe_count = static_cast<int>(v[3]);
  }
  if (v.size() == 5) p.phase = v[4];
  return p;
}

}  // namespace probecomp::cli
