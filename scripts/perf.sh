#!/usr/bin/env bash
# Whole-process speed and memory of `probecomp compensate` (the performance table, docs/performance.md): the demo's panel
# simulated at 10 000 and 1 000 000 points (misaligned 0.2 mm / 1.5°, a 0.3 mm bump, σ = 4.5 µm), each compensated
# RUNS times; prints the wall time and peak RSS (/usr/bin/time) and the JSON's stage timings of every run, and the
# errors against the simulation's truth of the last. Uses an existing Release build (default build/).
# PERF_10M=1 adds 10 219 456 points (spacing 0.02245 mm; one run; the simulation alone takes about a minute and
# 5.5 GB, the files 2.8 GB in a temporary directory).
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
cases=("10k 0.71 $runs" "1M 0.071 $runs")
[ "${PERF_10M:-0}" = 1 ] && cases+=("10M 0.02245 1")
for case in "${cases[@]}"; do
  set -- $case
  n_runs=$3
  dir="$work/$1"
  "$pc" simulate --cad "$work/demo/nominal.igs" --spacing "$2" --probe-radius 1 --misalign 0,0,0.2,0,1.5,0 \
    --deform bump:20,5,0,0.3,12 --noise 0.0045 --seed 1 --output-dir "$dir" >/dev/null
  echo "== $1: $(($(wc -l < "$dir/raw.csv") - 1)) points"
  for ((k = 1; k <= n_runs; ++k)); do
    /usr/bin/time -f "whole process %e s, peak RSS %M KB" "$pc" compensate --cad "$work/demo/nominal.igs" \
      --points "$dir/raw.csv" --probe-radius 1 --output "$dir/out.csv" --json "$dir/out.json" --quiet
    python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); r=d["registration"]; print("  timings", d["timings"], "| registration steps", r["iterations"], "searches", r["searches"])' "$dir/out.json"
  done
  python3 - "$dir/truth.csv" "$dir/out.csv" <<'EOF'
import csv, math, sys
# Streamed, row by row: 10 M rows would not fit in memory as lists.
def rows(p):
    f = open(p)
    r = csv.reader(l for l in f if not l.startswith('#'))
    return next(r), r
th, t = rows(sys.argv[1])
oh, o = rows(sys.argv[2])
ti = [th.index(c) for c in ('x', 'y', 'z', 'nx', 'ny', 'nz')]
oi = [oh.index(c) for c in ('x', 'y', 'z')]
st = oh.index('status')
n, s1, s2, largest = 0, 0.0, 0.0, 0.0
for a, b in zip(o, t):
    if a[st] == 'ok':
        e = sum((float(a[oi[k]]) - float(b[ti[k]])) * float(b[ti[3 + k]]) for k in range(3))
        n, s1, s2, largest = n + 1, s1 + e, s2 + e * e, max(largest, abs(e))
m = s1 / n
s = math.sqrt(max(s2 / n - m * m, 0.0))
print(f"  error along the actual normal, {n} ok rows: mean {m * 1e3:.3f} um, std {s * 1e3:.3f} um, "
      f"largest {largest * 1e3:.3f} um")
EOF
done
