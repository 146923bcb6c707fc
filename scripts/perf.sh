#!/usr/bin/env bash
# Whole-process speed and memory of `probecomp compensate` (the README's performance table): the demo's panel
# simulated at 10 000 and 1 000 000 points (misaligned 0.2 mm / 1.5°, a 0.3 mm bump, σ = 4.5 µm), each compensated
# RUNS times; prints the wall time and peak RSS (/usr/bin/time) and the JSON's stage timings of every run, and the
# errors against the simulation's truth of the last. Uses an existing Release build (default build/).
#   scripts/perf.sh [BUILD_DIR] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
runs=${2:-3}
pc="$build/probecomp"
[ -x "$pc" ] || { echo "perf.sh: no $pc; build first (scripts/demo.sh)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$pc" demo --output-dir "$work/demo" >/dev/null
for case in "10k 0.71" "1M 0.071"; do
  set -- $case
  dir="$work/$1"
  "$pc" simulate --cad "$work/demo/nominal.igs" --spacing "$2" --probe-radius 1 --misalign 0,0,0.2,0,1.5,0 \
    --deform bump:20,5,0,0.3,12 --noise 0.0045 --seed 1 --output-dir "$dir" >/dev/null
  echo "== $1: $(($(wc -l < "$dir/raw.csv") - 1)) points"
  for ((k = 1; k <= runs; ++k)); do
    /usr/bin/time -f "whole process %e s, peak RSS %M KB" "$pc" compensate --cad "$work/demo/nominal.igs" \
      --points "$dir/raw.csv" --probe-radius 1 --output "$dir/out.csv" --json "$dir/out.json" --quiet
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); r=d["registration"]; print("  timings", d["timings"], "| registration steps", r["iterations"], "searches", r["searches"])' "$dir/out.json"
  done
  python3 - "$dir/truth.csv" "$dir/out.csv" <<'EOF'
import csv, math, sys
def rows(p):
    with open(p) as f:
        r = csv.reader(l for l in f if not l.startswith('#'))
        h = next(r)
        return h, list(r)
th, t = rows(sys.argv[1])
oh, o = rows(sys.argv[2])
ti = [th.index(c) for c in ('x', 'y', 'z', 'nx', 'ny', 'nz')]
oi = [oh.index(c) for c in ('x', 'y', 'z')]
st = oh.index('status')
e = []
for a, b in zip(o, t):
    if a[st] == 'ok':
        e.append(sum((float(a[oi[k]]) - float(b[ti[k]])) * float(b[ti[3 + k]]) for k in range(3)))
m = sum(e) / len(e)
s = math.sqrt(sum((x - m) ** 2 for x in e) / len(e))
print(f"  error along the actual normal, {len(e)} ok rows: mean {m * 1e3:.3f} um, std {s * 1e3:.3f} um, "
      f"largest {max(abs(x) for x in e) * 1e3:.3f} um")
EOF
done
