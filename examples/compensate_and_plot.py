#!/usr/bin/env python3
"""A notebook-style example: load a part and its probe centres, compensate, look at the deviations.

    python3 examples/compensate_and_plot.py PART.igs RAW.csv PROBE_RADIUS [deviations.png]

e.g. on the demo's files (probecomp demo --output-dir build/demo):
    PYTHONPATH=build/python python3 examples/compensate_and_plot.py build/demo/nominal.igs build/demo/raw.csv 1
Without matplotlib (Debian's python3-matplotlib) it prints the figures and skips the plot. The "# %%" lines mark
cells, as Jupyter (jupytext) and editors that run cells read them.
"""
# %%
import sys

import numpy as np

import probecomp

cad, points, radius = sys.argv[1], sys.argv[2], float(sys.argv[3])
png = sys.argv[4] if len(sys.argv) > 4 else "deviations.png"

# %% 1. The nominal part and the measurement.
model = probecomp.CadModel(cad)
raw = probecomp.read_points(points)
print("%s: %d faces; %s: %d points in %s" % (cad, model.face_count, points, len(raw), raw.units))

# %% 2. Compensate: register to the radius-offset model, fit, offset along the fitted normal.
res = probecomp.compensate(model, raw.points, probe_radius=radius, normals=raw.normals, units=raw.units)
ok = np.array([s == "ok" for s in res.status])
d = res.deviation[ok] * 1000  # um
print("%d points, %d ok: deviation mean %.2f um, std %.2f um, min %.2f um, max %.2f um; mean u %.2f um"
      % (len(res), ok.sum(), d.mean(), d.std(), d.min(), d.max(), np.nanmean(res.uncertainty) * 1000))
print("registration: %s, RMS %.4f mm" % (res.stats["registration"]["status"], res.stats["registration"]["rms"]))
for w in res.warnings:
    print("warning:", w)

# %% 3. Plot: the deviation map seen from above and its histogram.
try:
    import matplotlib
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no plot")
    sys.exit(0)
fig, (top, hist) = plt.subplots(1, 2, figsize=(12, 4.5), gridspec_kw={"width_ratios": [3, 2]})
limit = np.percentile(np.abs(d), 99)
shown = top.scatter(res.points[ok, 0], res.points[ok, 1], c=d, cmap="RdBu_r", vmin=-limit, vmax=limit, s=4)
fig.colorbar(shown, ax=top, label="deviation (um)")
top.set(aspect="equal", xlabel="x (mm)", ylabel="y (mm)", title="deviation from the registered nominal")
hist.hist(d, bins=60, color="#1f6fb2")
hist.set(xlabel="deviation (um)", ylabel="points", title="%d trusted points" % ok.sum())
fig.tight_layout()
fig.savefig(png, dpi=100)
print("wrote", png, "(matplotlib %s)" % matplotlib.__version__)
