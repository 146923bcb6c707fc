"""probecomp: CAD-based contact-probe radius compensation for coordinate measuring machines, on numpy arrays.

A touch or scanning probe records the centre of its tip sphere, not the point where it touched the part.
probecomp registers the raw probe centres to the part's CAD model offset by the tip radius, fits a NURBS surface
through them, and offsets along the fitted normal (Ristic, Ainsworth and Brujic, Proc IMechE B 215, 2001).

    import probecomp
    model = probecomp.CadModel("part.stp")               # STEP or IGES; geometry in mm
    raw = probecomp.read_points("raw.csv")                # CSV, DMIS (.dmo) or QIF 3.0
    res = probecomp.compensate(model, raw.points, probe_radius=1.0, normals=raw.normals, units=raw.units)
    res.points, res.deviation, res.status, res.stats

The same computation as the command line's `probecomp compensate` (the same library), with the same messages:
errors raise probecomp.Error or one of its kinds (InputError, CadError, RegistrationError, FitError); arguments
that are not what they should be raise ValueError.
"""

import json as _json
from dataclasses import dataclass as _dataclass, field as _field

import numpy as _np

from . import _probecomp as _core
from ._probecomp import CadError, CadModel, Error, FitError, InputError, RegistrationError, Surface

__version__ = _core.__version__
__all__ = ["CadModel", "CompensationResult", "FitResult", "PointSet", "Surface", "compensate", "fit", "read_points",
           "write_points", "Error", "InputError", "CadError", "RegistrationError", "FitError", "__version__"]

# Length units as DMIS names them, and their length in mm (the inch exactly 25.4 mm).
_UNITS = {"mm": 1.0, "cm": 10.0, "meter": 1000.0, "inch": 25.4, "feet": 304.8}


def _scale(units):
    if units not in _UNITS:
        raise ValueError("units must be one of %s, not %r" % (", ".join(_UNITS), units))
    return _UNITS[units]


def _points(name, a, scale=1.0):
    a = _np.asarray(a, dtype=_np.float64)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError("%s must be an (N, 3) array, not of shape %s" % (name, a.shape))
    return _np.ascontiguousarray(a * scale if scale != 1.0 else a)


class CompensationResult:
    """One run of compensate(): every input row back, in order, in the caller's length unit.

    points       (N, 3) compensated contact points, machine frame (NaN where not computed: see status)
    normals      (N, 3) the outward unit normal each point was offset along (NaN where not computed)
    deviation    (N,)   signed distance from the registered nominal, + outside the material (NaN where not computed)
    uncertainty  (N,)   standard uncertainty u (k = 1) of each contact point along its normal (NaN where not computed)
    face         (N,)   the CAD face of each point (-1: none)
    radius       (N,)   the tip radius each point was compensated with
    status       list of N str: ok, outlier, edge, double-contact, few-points, not-on-model or failed
    transform    (4, 4) CAD to machine, the registration's result (translation in the caller's unit)
    warnings     list of str: what to know to read the result right (also in stats["warnings"])
    stats        dict: the command line's --json (inputs, transform, registration, faces, counts, deviation,
                 warnings, timings), lengths in mm as there
    """

    def __init__(self, run, scale, tolerance):
        self._run, self._tolerance = run, tolerance
        self.points = run.points / scale
        self.normals = run.normals
        self.deviation = run.deviation / scale
        self.uncertainty = run.uncertainty / scale
        self.face = run.face
        self.radius = run.radius / scale
        self.status = run.status
        self.transform = run.transform
        self.transform[:3, 3] /= scale
        self.warnings = run.warnings
        self.stats = _json.loads(run.statistics_json(tolerance))

    def __len__(self):
        return len(self.status)

    def report_html(self, model, characteristics=None):
        """The command line's --report page for this run, as a str (self-contained HTML).

        characteristics  as for judge(): the page then has their table and the 3-D view can be coloured by each,
                         and it is in the alignment frame where the specification asks for one, as
                         `compensate --characteristics SPEC --report` gives it
        """
        spec = None if characteristics is None else str(characteristics)
        return self._run.report_html(model, self._tolerance, spec)

    def judge(self, model, characteristics):
        """The drawing's characteristics judged on this run's trusted points: `compensate --characteristics`.

        model            the CadModel the run was compensated against
        characteristics  path of a specification file (JSON: datums, characteristics, alignment; docs/cli.md), or
                         "pmi" for the surface profiles and flatnesses the model's STEP AP242 file states

        Returns a dict with the --json keys "characteristics" (name, type, faces, datums, tolerance, outside, points,
        decision, and min, max, value, u, k or reason, and reason too when indeterminate; mm) and, where frames were
        set up, "datums" and "alignment".
        The arrays of this result are not moved into an alignment frame; the command line's output is.
        Raises InputError for a bad specification file, CadError for a file whose PMI cannot be read.
        """
        stats = _json.loads(self._run.judge_json(model, str(characteristics)))
        return {k: stats[k] for k in ("characteristics", "datums", "alignment") if k in stats}


class FitResult(CompensationResult):
    """A CompensationResult with the fitted part surfaces: `surfaces`, one Surface per fitted face (machine frame,
    mm: the measured contact surface), and `surface_faces`, the CAD face index of each. A Surface evaluates on
    parameter arrays: surface.evaluate(u, v) and surface.normal(u, v) give an array of u's shape plus a last axis
    of 3 (NaN outside surface.domain = (u0, u1, v0, v1))."""

    def __init__(self, run, scale, tolerance):
        super().__init__(run, scale, tolerance)
        self.surfaces = run.surfaces
        self.surface_faces = run.surface_faces


def _run(model, centres, probe_radius, normals, method, units, initial_transform, accept_doubtful_registration,
         tolerance, fit, qualification=None, styli=None, characteristics=None):
    if not isinstance(model, CadModel):
        raise ValueError("model must be a probecomp.CadModel, not %s" % type(model).__name__)
    scale = _scale(units)
    centres = _points("centres", centres, scale)
    default, radii = None, _np.empty(0)
    if probe_radius is None and qualification is None:
        raise ValueError("probe_radius is needed: the tip radius of every point, or an (N,) array of each point's")
    if probe_radius is not None and _np.ndim(probe_radius) == 0:
        default = float(probe_radius) * scale
    elif probe_radius is not None:
        radii = _np.ascontiguousarray(_np.asarray(probe_radius, dtype=_np.float64) * scale)
        if radii.ndim != 1 or len(radii) != len(centres):
            raise ValueError("probe_radius must be a number or an (N,) array for N = %d centres, not of shape %s"
                             % (len(centres), radii.shape))
    if normals is not None:
        normals = _points("normals", normals)
    if initial_transform is not None:
        initial_transform = _np.ascontiguousarray(_np.asarray(initial_transform, dtype=_np.float64))
    if tolerance is not None:
        if isinstance(tolerance, str):
            tolerance = _core.parse_tolerance(tolerance)
        else:
            tolerance = _core.parse_tolerance("%r,%r" % tuple(float(t) for t in tolerance))
    if styli is not None:
        styli = [str(s) for s in styli]
        if len(styli) != len(centres):
            raise ValueError("styli must name one stylus per centre: %d for %d" % (len(styli), len(centres)))
    run = _core.compensate(model, centres, radii, default, normals, method, initial_transform,
                           bool(accept_doubtful_registration), fit, "<numpy array>", units,
                           "" if qualification is None else str(qualification), styli or [],
                           "" if characteristics is None else str(characteristics))
    return (FitResult if fit else CompensationResult)(run, scale, tolerance)


def compensate(model, centres, probe_radius=None, normals=None, method="cad", *, units="mm", initial_transform=None,
               accept_doubtful_registration=False, tolerance=None, qualification=None, styli=None,
               characteristics=None):
    """Compensates probe centres for the tip radius against the part's CAD model: `probecomp compensate`.

    model           CadModel: the part's nominal faces (STEP or IGES)
    centres         (N, 3) probe-centre points as measured, machine frame, in `units`
    probe_radius    the tip radius of every point, or an (N,) array of each point's (several styli), in `units`
    normals         optional (N, 3) programmed approach normals (DMIS PTMEAS i, j, k; outward): they decide the
                    material side of open faces and are needed by method="conventional"
    method          "cad" (register to the radius-offset model, fit, offset along the fitted normal) or
                    "conventional" (the centre moved by the radius against the approach normal)
    units           the length unit of centres, probe_radius and the results: mm, cm, meter, inch or feet
    initial_transform  optional (4, 4) first guess of the transform CAD to machine (mm), for a part far from its
                    CAD position; default the identity (with a coarse alignment where that is not credible)
    accept_doubtful_registration  return a result even when the registration is not credible (its rows say so)
                    instead of raising RegistrationError
    tolerance       optional (lower, upper) deviation band in mm, or "lower,upper": out-of-tolerance counts in stats
    qualification   optional path of a QUAL.json (`probecomp qualify`): each point's radius is its stylus's effective
                    radius in the direction it was touched from (-normals, else against the fitted normal), and its
                    uncertainty joins u; probe_radius is then only the default for styli the file does not hold
    styli           with qualification: each centre's stylus name (N str); None when the file qualifies one stylus
    characteristics optional specification as for judge() (a path, or "pmi"): where the best fit of all the points is
                    doubtful, its datum features' points locate the part alone, as `compensate --characteristics`
                    does (stats["registration"]["located_by"] says which); its warnings (tolerances not evaluated,
                    the PMI reader's) join the result's; judge the result with the same one

    Returns a CompensationResult (see its help). The work runs with the GIL released.
    Raises InputError (points or options the method cannot use), CadError, RegistrationError (the points could not
    be registered credibly), ValueError (arguments of the wrong shape or kind).
    """
    return _run(model, centres, probe_radius, normals, method, units, initial_transform,
                accept_doubtful_registration, tolerance, False, qualification, styli, characteristics)


def fit(model, centres, probe_radius=None, normals=None, *, units="mm", initial_transform=None,
        accept_doubtful_registration=False, tolerance=None):
    """The measured surfaces: `probecomp fit`. The CAD-based compensation of compensate(), and each fitted face's
    contact surface (machine frame, mm) as a Surface in FitResult.surfaces (the CAD face of each in
    FitResult.surface_faces), evaluated by surface.evaluate(u, v) and surface.normal(u, v) on numpy arrays.
    Arguments as compensate(). Raises FitError where a fitted surface has no normal."""
    return _run(model, centres, probe_radius, normals, "cad", units, initial_transform,
                accept_doubtful_registration, tolerance, True)


@_dataclass
class PointSet:
    """A point file's content, in its own length unit `units`: points (N, 3); normals (N, 3) or None; radii (N,)
    or None (NaN where a row gives none); columns, the other columns by name (lists of N str, as written)."""
    points: _np.ndarray
    normals: object = None
    radii: object = None
    units: str = "mm"
    columns: dict = _field(default_factory=dict)

    def __len__(self):
        return len(self.points)


def read_points(path, units=None):
    """Reads a point file: CSV (x,y,z[,i,j,k][,r] and other columns; a '# lengths in UNIT' line), DMIS .dmo
    (PTMEAS/FA points, UNITS, SNSDEF/SNSLCT tips) or QIF 3.0 (MeasuredPointSets), as `probecomp compensate
    --points` does. `units` is the file's length unit when the file does not state it (default mm). Returns a
    PointSet in the file's unit. Raises InputError naming the file and line of a bad row."""
    points, normals, radii, unit, columns = _core.read_points(str(path), units or "")
    scale = _UNITS.get(unit, 1.0)
    return PointSet(points / scale, normals, None if radii is None else radii / scale, unit, dict(columns))


def write_points(path, points, normals=None, radii=None, *, units="mm", columns=None):
    """Writes points as CSV, DMIS (.dmo) or QIF 3.0 (.qif) by the extension, as `probecomp convert` does: points
    (N, 3), optional normals (N, 3), radii (N,) and columns (name: N values), lengths in `units`. The file appears
    whole or not at all."""
    scale = _scale(units)
    points = _points("points", points, scale)
    if normals is not None:
        normals = _points("normals", normals)
    if radii is not None:
        radii = _np.ascontiguousarray(_np.asarray(radii, dtype=_np.float64) * scale)
    carried = [(str(name), [str(v) for v in values]) for name, values in (columns or {}).items()]
    _core.write_points(str(path), points, normals, radii, units, carried)
