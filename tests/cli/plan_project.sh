#!/bin/sh
# plan then project: every planned point comes back, in order, on its own face at distance 0, and the DMIS
# program has one PTMEAS per point. Usage: plan_project.sh PROBECOMP CAD_FILE WORK_DIR SPACING
set -eu
P=$1; CAD=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
"$P" plan "$CAD" --spacing "$4" --output "$W/plan.csv"
"$P" plan "$CAD" --spacing "$4" --output "$W/plan.dmi"
n=$(($(wc -l <"$W/plan.csv") - 1))
m=$(grep -c '^PTMEAS/CART,' "$W/plan.dmi")
[ "$n" -gt 100 ] || { echo "FAIL: only $n planned points"; exit 1; }
[ "$n" -eq "$m" ] || { echo "FAIL: $n CSV points but $m PTMEAS"; exit 1; }
"$P" project --cad "$CAD" --points "$W/plan.csv" --output "$W/projected.csv"
rows=$(($(wc -l <"$W/projected.csv") - 1))
[ "$rows" -eq "$n" ] || { echo "FAIL: $n points in, $rows rows out"; exit 1; }
# distance (column 7) is zero to 1e-6 mm; the carried input face column equals the found face, except where
# the point is on an edge shared by two faces (then either may be nearest, at distance 0 both).
awk -F, 'NR > 1 { d = $7 < 0 ? -$7 : $7; if (d > 1e-6) { print "FAIL: row " NR - 1 " distance " $7; bad = 1 } }
         END { exit bad }' "$W/projected.csv"
echo "plan/project: $n points, all on the model"
