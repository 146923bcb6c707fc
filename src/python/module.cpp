// probecomp's Python bindings (pybind11): the extension module probecomp._probecomp, wrapped by the package
// python/probecomp/__init__.py, which gives it its keyword arguments, units and documentation. numpy arrays in and
// out (float64); the work runs with the GIL released; the library's errors become probecomp.Error and its kinds,
// with the library's messages.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "probecomp/cad/model.hpp"
#include "probecomp/compensation/conventional.hpp"
#include "probecomp/compensation/pipeline.hpp"
#include "probecomp/probe/qualification_file.hpp"
#include "probecomp/error.hpp"
#include "probecomp/geometry/stopwatch.hpp"
#include "probecomp/inspection/characteristics.hpp"
#include "probecomp/io/output_files.hpp"
#include "probecomp/io/point_files.hpp"
#include "probecomp/io/point_table.hpp"
#include "probecomp/results/report.hpp"
#include "probecomp/results/files.hpp"
#include "probecomp/results/statistics.hpp"
#include "probecomp/io/text.hpp"
#include "probecomp/nurbs/surface.hpp"
#include "probecomp/version.hpp"

namespace py = pybind11;

namespace probecomp::python {

namespace {

// The words a Hint (probecomp/error.hpp) takes in Python: the keyword arguments of probecomp.compensate and
// probecomp.read_points.
std::string hint_words(Hint hint) {
  switch (hint) {
    case Hint::InitialTransform:
      return ". Give a rough alignment with initial_transform=T (a (4, 4) array, CAD -> machine), or check the CAD "
             "file, the frame and the probe radius";
    case Hint::InitialTransformOrAcceptDoubtful:
      return ". Give a rough alignment with initial_transform=T (a (4, 4) array, CAD -> machine); if the part really "
             "deviates from its model by about the probe radius, accept_doubtful_registration=True runs on with a "
             "warning";
    case Hint::DeclaredUnit: return " as units= says";
    case Hint::None: break;
  }
  return "";
}

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// An (N, 3) float64 array seen as N points without a copy: Eigen's Vector3d is three packed doubles.
static_assert(sizeof(Point3) == 3 * sizeof(double) && alignof(Point3) <= alignof(double));
std::span<const Point3> as_points(const Array& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw std::invalid_argument(std::string(name) + " must be an (N, 3) array, not of shape " +
                                std::string(py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))));
  }
  return {reinterpret_cast<const Point3*>(a.data()), static_cast<std::size_t>(a.shape(0))};
}

py::array_t<double> vectors(const std::vector<compensation::CompensatedPoint>& pts,
                            Vector3 compensation::CompensatedPoint::*member) {
  py::array_t<double> out({static_cast<py::ssize_t>(pts.size()), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < pts.size(); ++k) {
    // As the command line's empty fields: nothing where the row was not computed.
    for (int c = 0; c < 3; ++c) o(static_cast<py::ssize_t>(k), c) = pts[k].computed() ? (pts[k].*member)(c) : std::nan("");
  }
  return out;
}

template <class T>
py::array_t<T> column(const std::vector<compensation::CompensatedPoint>& pts, T (*of)(const compensation::CompensatedPoint&)) {
  py::array_t<T> out(static_cast<py::ssize_t>(pts.size()));
  auto o = out.template mutable_unchecked<1>();
  for (std::size_t k = 0; k < pts.size(); ++k) o(static_cast<py::ssize_t>(k)) = of(pts[k]);
  return out;
}

py::array_t<double> matrix(const Eigen::Matrix4d& M) {
  py::array_t<double> out({py::ssize_t{4}, py::ssize_t{4}});
  auto o = out.mutable_unchecked<2>();
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) o(a, b) = M(a, b);
  }
  return out;
}

// A run's result with what its statistics need (the inputs as the command line states them).
struct Run {
  compensation::CompensationResult result;
  results::RunInputs inputs;
  double seconds = 0.0;
  std::vector<nurbs::Surface> part_surfaces;  // fit(): the fitted contact surfaces, one per fitted face
  std::vector<int> part_faces;                // their faces' indices
};

// As compensate --characteristics: a specification file, or "pmi" for the model's STEP file's own, judged on the
// run's points.
inspection::Specification specification(const cad::Model& model, const std::string& characteristics) {
  return inspection::load_specification(characteristics, model).spec;
}

inspection::Inspection judge(const Run& r, const cad::Model& model, const std::string& characteristics) {
  return inspection::evaluate(specification(model, characteristics), model, r.result);
}

Run run_compensate(const cad::Model& model, const Array& centres, const Array& radii, std::optional<double> probe_radius,
                   const std::optional<Array>& normals, const std::string& method, const std::optional<Array>& initial,
                   bool accept_doubtful, bool fit, const std::string& points_name, const std::string& unit,
                   const std::string& qualification, const std::vector<std::string>& styli,
                   const std::string& characteristics) {
  const std::span<const Point3> points = as_points(centres, "centres");
  std::optional<std::span<const Vector3>> approach;
  if (normals) {
    approach = as_points(*normals, "normals");
    if (approach->size() != points.size()) {
      throw InputError("normals: " + std::to_string(approach->size()) + " rows for " + std::to_string(points.size()) +
                       " centres");
    }
  }
  compensation::CompensateOptions o;
  if (method != "cad" && method != "conventional") {
    throw std::invalid_argument("method must be 'cad' or 'conventional', not '" + method + "'");
  }
  o.method = method == "conventional" ? compensation::Method::Conventional : compensation::Method::Cad;
  o.accept_doubtful_registration = accept_doubtful;
  // As compensate --characteristics: the datum features locate a part whose best fit is doubtful, and the
  // specification's warnings (a PMI reader's, tolerances not evaluated) join the run's.
  std::vector<std::string> specification_warnings;
  if (!characteristics.empty()) {
    inspection::LoadedSpecification loaded = inspection::load_specification(characteristics, model);
    o.datum_faces = inspection::datum_faces(loaded.spec);
    specification_warnings = std::move(loaded.warnings);
  }
  Run run;
  run.inputs.cad = model.path.string();
  run.inputs.points = points_name;
  if (const auto u = io::length_unit(unit)) run.inputs.points_unit = *u;
  run.inputs.probe_radius = probe_radius;
  if (radii.size() > 0) {
    if (radii.ndim() != 1 || static_cast<std::size_t>(radii.shape(0)) != points.size()) {
      throw InputError("probe_radius: " + std::to_string(radii.size()) + " radii for " + std::to_string(points.size()) +
                       " centres");
    }
    o.probe_radii.assign(radii.data(), radii.data() + radii.size());
    run.inputs.tip_radii = results::distinct_radii(o.probe_radii);
    o.probe_radius = run.inputs.tip_radii.empty() ? 0.0 : run.inputs.tip_radii.front();
  } else if (probe_radius) {
    o.probe_radius = *probe_radius;
    run.inputs.tip_radii = {*probe_radius};
  } else if (qualification.empty()) {
    throw std::invalid_argument("probe_radius is needed");
  }
  // Each point's radius from its stylus's qualification by direction (compensation/qualified_radii.hpp); the radii
  // above are then the default for styli it does not hold.
  std::optional<probe::Qualification> qualified;
  if (!qualification.empty()) {
    qualified = probe::read_qualification(qualification);
    o.qualification = &*qualified;
    o.styli = styli;
    if (radii.size() == 0) o.probe_radius = probe_radius.value_or(0.0);
    std::vector<double> each = qualified->effective_radii();
    each.insert(each.end(), run.inputs.tip_radii.begin(), run.inputs.tip_radii.end());
    run.inputs.tip_radii = results::distinct_radii(each);
  }
  if (initial) {
    if (initial->ndim() != 2 || initial->shape(0) != 4 || initial->shape(1) != 4) {
      throw std::invalid_argument("initial_transform must be a (4, 4) array");
    }
    Eigen::Matrix4d M;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) M(a, b) = initial->at(a, b);
    }
    o.registration.initial = geometry::RigidTransform(M);
  }
  {
    py::gil_scoped_release unlocked;
    const geometry::Stopwatch clock;
    run.result = compensation::compensate(model, points, approach, o);
    run.result.warnings.insert(run.result.warnings.end(), specification_warnings.begin(), specification_warnings.end());
    if (fit) {
      run.part_surfaces = compensation::fitted_part_surfaces(run.result);
      for (const compensation::FaceReport& f : run.result.faces) {
        if (f.fitted) run.part_faces.push_back(f.face);
      }
    }
    run.seconds = clock.seconds();
  }
  return run;
}

// Surface points (or unit normals) at parameter arrays u and v of one shape: an array of that shape with a last axis
// of 3.
py::array_t<double> on_surface(const nurbs::Surface& s, const Array& u, const Array& v, bool normals) {
  if (u.ndim() != v.ndim() || !std::equal(u.shape(), u.shape() + u.ndim(), v.shape())) {
    throw std::invalid_argument("u and v must have the same shape");
  }
  std::vector<py::ssize_t> shape(u.shape(), u.shape() + u.ndim());
  shape.push_back(3);
  py::array_t<double> out(shape);
  double* o = out.mutable_data();
  const double* pu = u.data();
  const double* pv = v.data();
  const nurbs::Domain d = s.domain();
  const auto n = static_cast<std::size_t>(u.size());
  {
    py::gil_scoped_release unlocked;
    for (std::size_t k = 0; k < n; ++k) {
      if (!(pu[k] >= d.u0 && pu[k] <= d.u1 && pv[k] >= d.v0 && pv[k] <= d.v1)) {
        for (int c = 0; c < 3; ++c) o[3 * k + static_cast<std::size_t>(c)] = std::nan("");
        continue;
      }
      const Vector3 x = normals ? nurbs::unit_normal(s, pu[k], pv[k]).n : nurbs::evaluate(s, pu[k], pv[k]);
      for (int c = 0; c < 3; ++c) o[3 * k + static_cast<std::size_t>(c)] = x(c);
    }
  }
  return out;
}

}  // namespace

}  // namespace probecomp::python

PYBIND11_MODULE(_probecomp, m) {
  using namespace probecomp;
  using namespace probecomp::python;
  m.doc() = "probecomp's compiled core; use the package probecomp.";
  m.attr("__version__") = version();

  // Kinds of error, base first: pybind11 tries translators newest first, so each kind is found before its base.
  auto& error = py::register_exception<Error>(m, "Error", PyExc_RuntimeError);
  py::register_exception<InputError>(m, "InputError", error.ptr());
  py::register_exception<CadError>(m, "CadError", error.ptr());
  py::register_exception<RegistrationError>(m, "RegistrationError", error.ptr());
  py::register_exception<FitError>(m, "FitError", error.ptr());
  // An error's hint in this package's words (its keyword arguments), after the message; registered last, so tried first.
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& e) {
      if (e.hint() == Hint::None) throw;
      const std::string what = e.what() + hint_words(e.hint());
      const char* kind = dynamic_cast<const RegistrationError*>(&e) ? "RegistrationError"
                         : dynamic_cast<const InputError*>(&e)      ? "InputError"
                         : dynamic_cast<const CadError*>(&e)        ? "CadError"
                         : dynamic_cast<const FitError*>(&e)        ? "FitError"
                                                                    : "Error";
      PyErr_SetString(py::module_::import("probecomp._probecomp").attr(kind).ptr(), what.c_str());
    }
  });

  py::class_<cad::Model, std::shared_ptr<cad::Model>>(m, "CadModel",
                                                     "A part's faces from a STEP or IGES file, as NURBS with their trims and "
                                                     "material sides, in mm (CadModel(path); raises CadError for a file "
                                                     "that cannot be read or used).")
      .def(py::init([](const std::string& path) {
             py::gil_scoped_release unlocked;
             return std::make_shared<cad::Model>(cad::Model::load(path));
           }),
           py::arg("path"))
      .def_property_readonly("path", [](const cad::Model& model) { return model.path.string(); })
      .def_property_readonly("face_count", &cad::Model::face_count)
      .def_property_readonly("units", [](const cad::Model& model) { return model.file_units; })
      .def_property_readonly(
          "read_warnings", [](const cad::Model& model) { return model.read_warnings; },
          "What the reader left out of the file (entities OpenCASCADE could not parse or convert), one line each; [] for a clean file")
      .def_property_readonly("face_names",
                             [](const cad::Model& model) {
                               std::vector<std::string> names;
                               for (const cad::Face& f : model.faces) names.push_back(f.name);
                               return names;
                             })
      .def_property_readonly("face_types",
                             [](const cad::Model& model) {
                               std::vector<std::string> types;
                               for (const cad::Face& f : model.faces) types.push_back(f.source_type);
                               return types;
                             })
      .def("surface",
           [](const cad::Model& model, int index) {
             if (index < 0 || index >= model.face_count()) {
               throw py::index_error("face " + std::to_string(index) + " of a model of " +
                                     std::to_string(model.face_count()) + " faces");
             }
             return model.faces[static_cast<std::size_t>(index)].surface;
           },
           py::arg("index"))
      .def_property_readonly("face_boxes", [](const cad::Model& model) {
        py::array_t<double> out({static_cast<py::ssize_t>(model.faces.size()), py::ssize_t{2}, py::ssize_t{3}});
        auto o = out.mutable_unchecked<3>();
        for (std::size_t f = 0; f < model.faces.size(); ++f) {
          const BoundingBox box = nurbs::bounding_box(model.faces[f].surface);
          for (int c = 0; c < 3; ++c) {
            o(static_cast<py::ssize_t>(f), 0, c) = box.min(c);
            o(static_cast<py::ssize_t>(f), 1, c) = box.max(c);
          }
        }
        return out;
      });

  py::class_<nurbs::Surface>(m, "Surface",
                             "A NURBS surface (mm): evaluate(u, v) and normal(u, v) on arrays of parameters, NaN outside "
                             "domain = (u0, u1, v0, v1).")
      .def_property_readonly("degrees", [](const nurbs::Surface& s) { return std::pair{s.p(), s.q()}; })
      .def_property_readonly("control_point_count", [](const nurbs::Surface& s) { return std::pair{s.num_u(), s.num_v()}; })
      .def_property_readonly("domain",
                             [](const nurbs::Surface& s) {
                               const nurbs::Domain d = s.domain();
                               return std::tuple{d.u0, d.u1, d.v0, d.v1};
                             })
      .def("evaluate", [](const nurbs::Surface& s, const Array& u, const Array& v) { return on_surface(s, u, v, false); },
           py::arg("u"), py::arg("v"))
      .def("normal", [](const nurbs::Surface& s, const Array& u, const Array& v) { return on_surface(s, u, v, true); },
           py::arg("u"), py::arg("v"));

  py::class_<Run>(m, "Run")
      .def_property_readonly("points", [](const Run& r) { return vectors(r.result.points, &compensation::CompensatedPoint::contact); })
      .def_property_readonly("normals", [](const Run& r) { return vectors(r.result.points, &compensation::CompensatedPoint::normal); })
      .def_property_readonly("deviation",
                             [](const Run& r) {
                               return column<double>(r.result.points, [](const compensation::CompensatedPoint& p) {
                                 return p.computed() ? p.deviation : std::nan("");
                               });
                             })
      .def_property_readonly("uncertainty",
                             [](const Run& r) {
                               return column<double>(r.result.points,
                                                     [](const compensation::CompensatedPoint& p) {
                                                       return p.computed() ? p.uncertainty : std::nan("");
                                                     });
                             })
      .def_property_readonly("radius",
                             [](const Run& r) {
                               return column<double>(r.result.points,
                                                     [](const compensation::CompensatedPoint& p) { return p.radius; });
                             })
      .def_property_readonly("face",
                             [](const Run& r) {
                               return column<std::int64_t>(r.result.points, [](const compensation::CompensatedPoint& p) {
                                 return static_cast<std::int64_t>(p.face);
                               });
                             })
      .def_property_readonly("status",
                             [](const Run& r) {
                               std::vector<std::string> s;
                               for (const compensation::CompensatedPoint& p : r.result.points) s.push_back(compensation::to_string(p.status));
                               return s;
                             })
      .def_property_readonly("transform", [](const Run& r) { return matrix(r.result.registration.transform.matrix()); })
      .def_property_readonly("warnings", [](const Run& r) { return r.result.warnings; })
      .def_property_readonly("surfaces", [](const Run& r) { return r.part_surfaces; })
      .def_property_readonly("surface_faces", [](const Run& r) { return r.part_faces; })
      .def("statistics_json",
           [](const Run& r, std::optional<std::pair<double, double>> tolerance) {
             std::optional<results::Tolerance> t;
             if (tolerance) t = results::Tolerance{tolerance->first, tolerance->second};
             return results::statistics_json(r.result, r.inputs, {.total = r.seconds}, t);
           },
           py::arg("tolerance") = std::nullopt)
      .def("judge_json",
           [](const Run& r, const cad::Model& model, const std::string& characteristics) {
             const inspection::Inspection judged = judge(r, model, characteristics);
             return results::statistics_json(r.result, r.inputs, {.total = r.seconds}, std::nullopt, &judged);
           },
           py::arg("model"), py::arg("characteristics"))
      .def("report_html",
           [](const Run& r, const cad::Model& model, std::optional<std::pair<double, double>> tolerance,
              const std::optional<std::string>& characteristics) {
             results::ReportContext c{.inputs = r.inputs, .tolerance = std::nullopt, .timings = {.total = r.seconds}};
             if (tolerance) c.tolerance = results::Tolerance{tolerance->first, tolerance->second};
             // As compensate --characteristics --report: the characteristics' table and colouring, and the page in
             // the alignment frame where the specification asks for one.
             std::optional<inspection::Inspection> judged;
             std::optional<compensation::CompensationResult> in_frame;
             if (characteristics) {
               judged = judge(r, model, *characteristics);
               c.inspection = &*judged;
               if (judged->alignment_frame) {
                 if (!judged->alignment_frame->ok()) {
                   throw InputError(*characteristics + ": alignment " + judged->alignment + ": " +
                                    judged->alignment_frame->reason);
                 }
                 in_frame = inspection::aligned(r.result, *judged->alignment_frame, model);
               }
             }
             const compensation::CompensationResult& shown = in_frame ? *in_frame : r.result;
             c.nominal = results::registered_outline(model, shown.registration.transform);
             return results::html_report(shown, c);
           },
           py::arg("model"), py::arg("tolerance") = std::nullopt, py::arg("characteristics") = std::nullopt);

  m.def("compensate", &run_compensate, py::arg("model"), py::arg("centres"), py::arg("radii"), py::arg("probe_radius"),
        py::arg("normals"), py::arg("method"), py::arg("initial_transform"), py::arg("accept_doubtful_registration"),
        py::arg("fit"), py::arg("points_name"), py::arg("unit"), py::arg("qualification"), py::arg("styli"),
        py::arg("characteristics"));

  m.def("parse_tolerance", [](const std::string& text) {
    results::Tolerance t;
    try {
      t = results::parse_tolerance(text);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("tolerance: ") + e.what());
    }
    return std::pair{t.lower, t.upper};
  });

  // A point file: (points mm, normals or None, radii mm or None, unit name, {carried column: values as text}).
  m.def("read_points", [](const std::string& path, const std::string& unit) {
    std::optional<io::LengthUnit> declared;
    if (!unit.empty()) {
      declared = io::length_unit(unit);
      if (!declared) throw std::invalid_argument("units must be mm, cm, meter, inch or feet, not '" + unit + "'");
    }
    io::PointTable t;
    {
      py::gil_scoped_release unlocked;
      t = io::read_points(path, declared);
    }
    const auto n = static_cast<py::ssize_t>(t.points.size());
    py::array_t<double> points({n, py::ssize_t{3}});
    if (n > 0) std::copy_n(t.points.front().data(), 3 * t.points.size(), points.mutable_data());
    py::object normals = py::none(), radii = py::none();
    if (t.normals && n > 0) {
      py::array_t<double> a({n, py::ssize_t{3}});
      std::copy_n(t.normals->front().data(), 3 * t.normals->size(), a.mutable_data());
      normals = a;
    }
    if (t.radii) {
      py::array_t<double> a(n);
      std::copy(t.radii->begin(), t.radii->end(), a.mutable_data());
      radii = a;
    }
    py::dict columns;
    for (int c : t.carried_columns()) {
      py::list values;
      for (const auto row : t.rows) values.append(py::str(row[static_cast<std::size_t>(c)]));
      columns[py::str(t.columns[static_cast<std::size_t>(c)])] = values;
    }
    return py::make_tuple(points, normals, radii, std::string(t.unit.name), columns);
  });

  // Writes points (mm) as CSV, DMIS or QIF by the extension, in `unit`; all or nothing.
  m.def("write_points", [](const std::string& path, const Array& points, const std::optional<Array>& normals,
                           const std::optional<Array>& radii, const std::string& unit,
                           const std::vector<std::pair<std::string, std::vector<std::string>>>& columns) {
    io::PointTable t;
    const auto u = io::length_unit(unit);
    if (!u) throw std::invalid_argument("units must be mm, cm, meter, inch or feet, not '" + unit + "'");
    t.unit = *u;
    const std::span<const Point3> p = as_points(points, "points");
    t.points.assign(p.begin(), p.end());
    t.columns = {"x", "y", "z"};
    if (normals) {
      const std::span<const Vector3> n = as_points(*normals, "normals");
      if (n.size() != p.size()) throw InputError("normals: " + std::to_string(n.size()) + " rows for " + std::to_string(p.size()) + " points");
      t.normals.emplace(n.begin(), n.end());
      t.columns.insert(t.columns.end(), {"i", "j", "k"});
    }
    if (radii) {
      if (radii->ndim() != 1 || static_cast<std::size_t>(radii->shape(0)) != p.size()) {
        throw InputError("radii: " + std::to_string(radii->size()) + " for " + std::to_string(p.size()) + " points");
      }
      t.radii.emplace(radii->data(), radii->data() + radii->size());
      t.columns.push_back("r");
    }
    const std::size_t ours = t.columns.size();
    for (const auto& [name, values] : columns) {
      if (values.size() != p.size()) {
        throw InputError("column " + name + ": " + std::to_string(values.size()) + " values for " + std::to_string(p.size()) + " points");
      }
      t.columns.push_back(name);
    }
    if (!columns.empty()) {
      std::vector<std::string> row;
      for (std::size_t k = 0; k < p.size(); ++k) {
        row.assign(ours, std::string());  // empty number fields: the values above are used
        for (const auto& column : columns) row.push_back(column.second[k]);
        t.rows.push_back(row);
      }
    }
    py::gil_scoped_release unlocked;
    const std::string text = io::points_text(t, io::point_format(path), path);
    io::OutputFiles files;
    files.add(path, text);
    files.commit();
  });
}
