"""The Python package against the command line (the same input must give the same numbers, to the CLI's 9 decimals)
and against the simulator's truth (a held-out style free-form case: different deformation, misalignment and seed
from the demo's). Run by CTest (python.pytest) with PYTHONPATH at the build tree's package and PROBECOMP_CLI, the
probecomp command; PROBECOMP_CAD_DIR, the test CAD files."""

import csv
import json
import re
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import probecomp

CLI = os.environ["PROBECOMP_CLI"]
CAD_DIR = os.environ["PROBECOMP_CAD_DIR"]
EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "examples")
# The CLI writes lengths with 9 decimals: equal to it means within half a unit of the last one, plus a hair.
CLI_DIGITS = 5.01e-10


def cli(*args, expect=0):
    run = subprocess.run([CLI, *[str(a) for a in args]], capture_output=True, text=True)
    assert run.returncode == expect, run.stderr
    return run


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("probecomp_python")


@pytest.fixture(scope="module")
def demo(work):
    cli("demo", "--output-dir", work / "demo")
    return work / "demo"


@pytest.fixture(scope="module")
def heldout(work, demo):
    """The demo's panel measured another way: misaligned 0.3 mm and 1.2 deg about x and z, a bump and a dent of its
    own, noise 4.5 um, seed 17; with the simulator's truth."""
    out = work / "heldout"
    cli("simulate", "--cad", demo / "nominal.igs", "--spacing", 1, "--probe-radius", 1,
        "--misalign", "0.1,-0.2,0.3,1.2,0,-0.8", "--deform", "bump:-25,10,0,0.25,10", "--deform", "bump:30,-8,0,-0.15,4",
        "--noise", 0.0045, "--seed", 17, "--output-dir", out)
    return out


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    return rows[0], rows[1:]


def cli_result(path):
    """The CLI's output CSV as arrays: points, normals, deviation, u (NaN where empty), face, status."""
    head, rows = read_csv(path)
    col = {name: i for i, name in enumerate(head)}
    num = lambda r, n: float(r[col[n]]) if r[col[n]] != "" else np.nan
    return {
        "points": np.array([[num(r, "x"), num(r, "y"), num(r, "z")] for r in rows]),
        "normals": np.array([[num(r, "nx"), num(r, "ny"), num(r, "nz")] for r in rows]),
        "deviation": np.array([num(r, "deviation") for r in rows]),
        "uncertainty": np.array([num(r, "u") for r in rows]),
        "face": np.array([int(r[col["face"]]) if r[col["face"]] else -1 for r in rows]),
        "status": [r[col["status"]] for r in rows],
    }


def assert_same_as_cli(res, out_csv, lengths=CLI_DIGITS):
    c = cli_result(out_csv)
    assert res.status == c["status"]
    assert np.array_equal(res.face, c["face"])
    for name, tol in (("points", lengths), ("deviation", lengths), ("uncertainty", lengths), ("normals", 1e-12)):
        ours, theirs = getattr(res, name), c[name]
        assert np.array_equal(np.isnan(ours), np.isnan(theirs)), name
        finite = ~np.isnan(theirs)
        assert np.all(np.abs(ours[finite] - theirs[finite]) <= tol), name


def truth_errors(res, truth_csv, point_ids):
    """Signed distance of each ok compensated point from the simulator's true contact point, along the actual normal
    (as tests/cli/score.awk), rows matched by their point id: um."""
    head, rows = read_csv(truth_csv)
    col = {name: i for i, name in enumerate(head)}
    truth = {r[col["point"]]: (np.array([float(r[col[n]]) for n in ("x", "y", "z")]),
                               np.array([float(r[col[n]]) for n in ("nx", "ny", "nz")]))
             for r in rows if r[col["status"]] == "ok"}
    errors = []
    for k, point in enumerate(point_ids):
        if res.status[k] == "ok" and point in truth:
            contact, normal = truth[point]
            errors.append(1000 * np.dot(res.points[k] - contact, normal))
    return np.array(errors)


def test_the_demo_gives_the_clis_numbers(demo, work):
    out, stats = work / "demo_out.csv", work / "demo.json"
    cli("compensate", "--cad", demo / "nominal.igs", "--points", demo / "raw.csv", "--probe-radius", 1,
        "--output", out, "--json", stats, "--quiet")
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(demo / "raw.csv")
    res = probecomp.compensate(model, raw.points, probe_radius=1.0, normals=raw.normals)
    assert len(res) == 7200
    assert_same_as_cli(res, out)
    theirs = json.load(open(stats))
    for key in ("counts", "deviation", "transform", "method", "units"):
        assert res.stats[key] == theirs[key], key
    assert np.abs(res.transform - np.array(theirs["transform"])).max() < 1e-12
    assert [f["face"] for f in res.stats["faces"]] == [f["face"] for f in theirs["faces"]]
    html = res.report_html(model)  # the command line's --report page
    assert '<canvas id="view"' in html and "<td>7200</td>" in html
    # The drawing's characteristics: the same as compensate --characteristics gives in --json.
    spec = work / "spec.json"
    spec.write_text('{"datums": {"A": {"faces": [0], "fit": "tangent"}}, "characteristics": ['
                    '{"name": "F", "faces": [0], "tolerance": 3.0}, {"name": "P", "faces": [0], "tolerance": 3.0, '
                    '"datums": ["A"]}]}')
    judged_cli = work / "judged.json"
    cli("compensate", "--cad", demo / "nominal.igs", "--points", demo / "raw.csv", "--probe-radius", 1,
        "--characteristics", spec, "--output", work / "judged.csv", "--json", judged_cli, "--quiet")
    judged = res.judge(model, spec)
    theirs = json.load(open(judged_cli))
    assert judged["characteristics"] == theirs["characteristics"]
    assert judged["datums"] == theirs["datums"] and judged["datums"][0]["fit"] == "tangent"
    # Their report: the command line's table of characteristics and datums, and the view's colouring by each.
    cli("compensate", "--cad", demo / "nominal.igs", "--points", demo / "raw.csv", "--probe-radius", 1,
        "--characteristics", spec, "--report", work / "judged.html", "--quiet")
    table = re.compile(r'<table id="(?:characteristics|datums)">.*?</table>', re.S)
    page, theirs = res.report_html(model, spec), (work / "judged.html").read_text()
    assert len(table.findall(page)) == 2 and table.findall(page) == table.findall(theirs)
    assert re.search(r'<select id="view-characteristic"><option value="0">F</option><option value="1">P</option>', page)
    assert not table.findall(html)
    with pytest.raises(probecomp.InputError, match="spec_bad.json"):
        (work / "spec_bad.json").write_text("{")
        res.judge(model, work / "spec_bad.json")
    # Given to compensate() too, the specification's datum features would locate a part whose best fit is doubtful;
    # this one's is credible, so all the points locate it and the numbers are the same. A bad one fails before the run.
    located = probecomp.compensate(model, raw.points, probe_radius=1.0, normals=raw.normals, characteristics=spec)
    assert located.stats["registration"]["located_by"] == "all-points"
    assert located.stats["registration"]["locating_points"] == 7200
    assert located.stats["registration"] == json.load(open(judged_cli))["registration"]
    assert np.array_equal(located.deviation, res.deviation)
    with pytest.raises(probecomp.InputError, match="spec_bad.json"):
        probecomp.compensate(model, raw.points, probe_radius=1.0, normals=raw.normals,
                             characteristics=work / "spec_bad.json")


def test_the_files_own_pmi_passes_its_warnings_on_as_the_command_line_prints_them(work):
    # FTC-06 (STEP AP242): 13 of its tolerances are not surface profiles or flatness. The command line warns so; a
    # Python run given characteristics="pmi" has the same warning among its own.
    ftc = os.path.join(CAD_DIR, "nist_ftc_06_asme1_ap242-e2.stp")
    cli("simulate", "--cad", ftc, "--spacing", 10, "--probe-radius", 1, "--noise", 0.002, "--output-dir", work / "ftc")
    raw = probecomp.read_points(work / "ftc" / "raw.csv")
    res = probecomp.compensate(probecomp.CadModel(ftc), raw.points, 1.0, raw.normals, characteristics="pmi")
    skipped = [w for w in res.warnings if "are not surface profiles or flatness and are not evaluated" in w]
    assert skipped == ["13 of the file's tolerances are not surface profiles or flatness and are not evaluated"]


def test_a_held_out_free_form_case_gives_the_clis_numbers_and_meets_the_truth(heldout, demo, work, capsys):
    out = work / "heldout_out.csv"
    cli("compensate", "--cad", demo / "nominal.igs", "--points", heldout / "raw.csv", "--probe-radius", 1,
        "--output", out, "--quiet")
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(heldout / "raw.csv")
    res = probecomp.compensate(model, raw.points, 1.0, raw.normals)
    assert_same_as_cli(res, out)
    ids = raw.columns["point"]
    ours = truth_errors(res, heldout / "truth.csv", ids)
    theirs_res = cli_result(out)

    class Cli:  # the CLI's rows, read back, scored the same way
        points, status = theirs_res["points"], theirs_res["status"]

    theirs = truth_errors(Cli, heldout / "truth.csv", ids)
    with capsys.disabled():
        print("\nheld-out free-form case, %d ok of %d: Python std %.3f um, max %.3f um; CLI std %.3f um, max %.3f um"
              % (len(ours), len(res), ours.std(), np.abs(ours).max(), theirs.std(), np.abs(theirs).max()))
    assert len(ours) >= 0.99 * len(res)
    assert ours.std() <= 2.0 and np.abs(ours).max() <= 10.0
    assert abs(ours.std() - theirs.std()) < 1e-6 and abs(np.abs(ours).max() - np.abs(theirs).max()) < 1e-6


def test_several_styli_inches_and_the_conventional_method_give_the_clis_numbers(heldout, demo, work):
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(heldout / "raw.csv")
    # Per-point radii: the file's points with a column r, half of them "measured" with a 1.0 mm tip, half 1.0 too
    # written as a different stylus name (the radii path, not the default).
    radii = np.where(raw.points[:, 0] < 0, 1.0, 1.0)
    probecomp.write_points(work / "styli.csv", raw.points, raw.normals, radii,
                           columns={"tip": ["A" if x < 0 else "B" for x in raw.points[:, 0]]})
    cli("compensate", "--cad", demo / "nominal.igs", "--points", work / "styli.csv", "--output", work / "styli_out.csv",
        "--quiet")
    res = probecomp.compensate(model, raw.points, radii, raw.normals)
    assert_same_as_cli(res, work / "styli_out.csv")
    assert res.stats["inputs"]["probe_radius"] is None and res.stats["inputs"]["tip_radii"] == [1]

    # Inches: the same points in inch, the CLI told by the file's unit line.
    inch = raw.points / 25.4
    probecomp.write_points(work / "inch.csv", inch, raw.normals, units="inch")
    assert open(work / "inch.csv").readline().strip() == "# lengths in inch"
    cli("compensate", "--cad", demo / "nominal.igs", "--points", work / "inch.csv", "--probe-radius", 1 / 25.4,
        "--output", work / "inch_out.csv", "--quiet")
    res_inch = probecomp.compensate(model, inch, 1 / 25.4, raw.normals, units="inch")
    assert_same_as_cli(res_inch, work / "inch_out.csv")
    assert np.nanmax(np.abs(res_inch.points * 25.4 - res.points)) < 1e-6

    cli("compensate", "--cad", demo / "nominal.igs", "--points", heldout / "raw.csv", "--probe-radius", 1,
        "--method", "conventional", "--output", work / "conv_out.csv", "--quiet")
    conv = probecomp.compensate(model, raw.points, 1.0, raw.normals, method="conventional")
    assert_same_as_cli(conv, work / "conv_out.csv")


def test_errors_raise_the_librarys_kinds_with_the_clis_messages(demo, work):
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(demo / "raw.csv")
    probecomp.write_points(work / "two.csv", raw.points[:2])
    run = cli("compensate", "--cad", demo / "nominal.igs", "--points", work / "two.csv", "--probe-radius", 1, expect=3)
    with pytest.raises(probecomp.InputError) as e:
        probecomp.compensate(model, raw.points[:2], 1.0)
    assert run.stderr.strip() == "probecomp: " + str(e.value)
    assert isinstance(e.value, probecomp.Error) and isinstance(e.value, RuntimeError)

    with pytest.raises(probecomp.CadError, match="no-such-part.stp: no such file"):
        probecomp.CadModel(str(work / "no-such-part.stp"))
    assert model.read_warnings == []
    # Four angle units this file declares in a form OpenCASCADE refuses (tests/cad/model_test.cpp counts them).
    tail = probecomp.CadModel(os.path.join(CAD_DIR, "asitus_tail_section_asm.stp"))
    assert len(tail.read_warnings) == 1 and "errors in 4 of the file's" in tail.read_warnings[0]
    with pytest.raises(probecomp.InputError, match="probe radius"):
        probecomp.compensate(model, raw.points, -1.0)
    with pytest.raises(probecomp.InputError, match="needs each point's approach normal"):
        probecomp.compensate(model, raw.points, 1.0, method="conventional")
    # Far from the part and told not to search: not credible.
    far = raw.points + np.array([0.0, 0.0, 40.0])
    with pytest.raises(probecomp.Error):
        probecomp.compensate(model, far, 1.0, raw.normals)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        probecomp.compensate(model, raw.points[:, :2], 1.0)
    with pytest.raises(ValueError, match="units"):
        probecomp.compensate(model, raw.points, 1.0, units="furlong")
    with pytest.raises(ValueError, match="method"):
        probecomp.compensate(model, raw.points, 1.0, method="magic")
    with pytest.raises(ValueError, match="probe_radius"):
        probecomp.compensate(model, raw.points, np.ones(3))
    with pytest.raises(ValueError, match="tolerance"):
        probecomp.compensate(model, raw.points, 1.0, tolerance=(0.05, -0.05))
    bad = work / "bad.csv"
    bad.write_text("x,y,z\n1,2,3\n4,five,6\n")
    with pytest.raises(probecomp.InputError, match="bad.csv:3"):
        probecomp.read_points(bad)
    # What the caller can do is said in this package's words, never the command line's.
    inch = work / "inch.csv"
    inch.write_text("# lengths in inch\nx,y,z\n1,2,3\n")
    with pytest.raises(probecomp.InputError, match="lengths are in inch, not in mm as units= says$") as e:
        probecomp.read_points(inch, units="mm")
    assert "--" not in str(e.value)


def test_point_files_round_trip_through_every_format(demo, work):
    raw = probecomp.read_points(demo / "raw.csv")
    radii = np.full(len(raw), 0.5)
    for ext in ("csv", "qif", "dmo"):
        path = work / ("round." + ext)
        probecomp.write_points(path, raw.points, raw.normals, radii)
        back = probecomp.read_points(path)
        assert back.points.shape == raw.points.shape
        assert np.abs(back.points - raw.points).max() <= (0 if ext != "dmo" else 5e-7), ext
        # The readers normalise (i, j, k): a unit vector normalised again moves by an ulp or so.
        assert np.abs(back.normals - raw.normals).max() <= (1e-15 if ext != "dmo" else 5e-7), ext
        assert np.all(back.radii == 0.5), ext
    sample = probecomp.read_points(os.path.join(CAD_DIR, "qif_QIF_PTS_SAMPLE.QIF"))
    assert len(sample) == 691 and sample.units == "mm"
    assert np.all(sample.radii == 2.49978271104)
    assert sorted(set(sample.columns["set"]), key=int) == sorted(
        ["29", "262", "510", "12", "256", "757", "767", "777", "787", "797", "829", "834"], key=int)
    assert tuple(sample.points[0]) == (3.54516458565, 0.0037440421, -1.82916012241)


def test_fit_gives_the_measured_surfaces_the_cli_writes(demo, heldout, work):
    cli("fit", "--cad", demo / "nominal.igs", "--points", heldout / "raw.csv", "--probe-radius", 1,
        "--output", work / "fitted.igs", "--quiet")
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(heldout / "raw.csv")
    res = probecomp.fit(model, raw.points, 1.0, raw.normals)
    assert res.surface_faces == [0] and len(res.surfaces) == 1
    written = probecomp.CadModel(str(work / "fitted.igs")).surface(0)
    ours = res.surfaces[0]
    u0, u1, v0, v1 = ours.domain
    u, v = np.meshgrid(np.linspace(u0, u1, 21), np.linspace(v0, v1, 11))
    p = ours.evaluate(u, v)
    assert p.shape == (11, 21, 3)
    assert np.abs(p - written.evaluate(u, v)).max() < 1e-6  # IGES keeps the poles to its text precision
    n = ours.normal(u, v)
    assert np.allclose(np.linalg.norm(n, axis=-1), 1.0)
    assert np.all(np.isnan(ours.evaluate([u1 + 1.0], [v0])))  # outside the domain


def test_the_work_runs_without_the_gil(demo):
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(demo / "raw.csv")
    ticks, done = [0], threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    start = time.perf_counter()
    probecomp.compensate(model, raw.points, 1.0, raw.normals)
    seconds = time.perf_counter() - start
    done.set()
    t.join()
    # With the GIL held the counter could not run at all during the call; released, it ticks every millisecond or so.
    assert ticks[0] > 0.2 * seconds * 1000, (ticks[0], seconds)


def test_help_reads_like_the_command_lines():
    doc = probecomp.compensate.__doc__
    for words in ("probe_radius", "(N, 3)", "units", "initial_transform", "accept_doubtful_registration",
                  "tolerance", "InputError", "RegistrationError"):
        assert words in doc
    assert "CAD face" in probecomp.CompensationResult.__doc__


def test_the_example_plots_the_deviations(demo, work):
    png = work / "deviations.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    run = subprocess.run([sys.executable, os.path.join(EXAMPLES, "compensate_and_plot.py"), str(demo / "nominal.igs"),
                          str(demo / "raw.csv"), "1.0", str(png)], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert "7200 points" in run.stdout
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000


def sphere_touches(path, styli):
    """Touches of a 25 mm sphere at (100, -50, 30), closed form: each stylus (name, radius, lobes in mm) touched 150
    times from the top to 10 degrees below the equator; its pre-travel 0.002 + lobes * sin^2 cos(3 (phi - 20 deg)),
    phi about the stylus (-z, right-handed: towards -y), as `simulate --pretravel 0.002,0,LOBES,3,20`."""
    golden, z_low = np.pi * (3 - np.sqrt(5)), -np.sin(np.radians(10))
    k = np.arange(150)
    z = 1 - (1 - z_low) * (k + 0.5) / 150
    rho = np.sqrt(np.maximum(0, 1 - z * z))
    n = np.stack([rho * np.cos(golden * k), rho * np.sin(golden * k), z], axis=1)
    rows = []
    for name, radius, lobes in styli:
        d = -n
        p = 0.002 + lobes * (1 - d[:, 2] ** 2) * np.cos(3 * (np.arctan2(-d[:, 1], d[:, 0]) - np.radians(20)))
        centres = np.array([100.0, -50.0, 30.0]) + (12.5 + radius - p)[:, None] * n
        rows += [(c, m, name) for c, m in zip(centres, n)]
    probecomp.write_points(path, np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
                           columns={"stylus": [r[2] for r in rows]})


def test_a_qualification_gives_the_clis_numbers(demo, work):
    sphere_touches(work / "sphere.csv", [("T1", 1.0, 0.004)])
    cli("qualify", "--points", work / "sphere.csv", "--sphere-diameter", 25, "--output", work / "qual.json")
    cli("simulate", "--cad", demo / "nominal.igs", "--spacing", 2, "--probe-radius", 1, "--misalign", "0,0,0.1,0,1,0",
        "--pretravel", "0.002,0,0.004,3,20", "--noise", 0.001, "--output-dir", work / "lobed")
    cli("compensate", "--cad", demo / "nominal.igs", "--points", work / "lobed" / "raw.csv", "--qualification",
        work / "qual.json", "--output", work / "lobed_out.csv", "--quiet")
    model = probecomp.CadModel(str(demo / "nominal.igs"))
    raw = probecomp.read_points(work / "lobed" / "raw.csv")
    res = probecomp.compensate(model, raw.points, normals=raw.normals, qualification=work / "qual.json")
    assert_same_as_cli(res, work / "lobed_out.csv")
    # Each point's effective radius: the nominal 1 mm less its pre-travel, 2 um +- 4 um by direction.
    assert np.all(np.abs(res.radius - 0.998) < 0.005) and np.ptp(res.radius) > 1e-4
    # Two styli qualified: the points must name theirs.
    sphere_touches(work / "two.csv", [("T1", 1.0, 0.004), ("T2", 0.5, 0.0)])
    cli("qualify", "--points", work / "two.csv", "--sphere-diameter", 25, "--output", work / "two.json")
    with pytest.raises(probecomp.InputError, match="name no stylus"):
        probecomp.compensate(model, raw.points, normals=raw.normals, qualification=work / "two.json")
    named = probecomp.compensate(model, raw.points, normals=raw.normals, qualification=work / "two.json",
                                 styli=["T1"] * len(raw.points))
    assert np.allclose(named.radius, res.radius, atol=1e-12, equal_nan=True)
