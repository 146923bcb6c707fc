#!/bin/sh
# plan then project: every planned point comes back, in order, on its own face at distance 0, and the DMIS
# program has one PTMEAS per point; on a model that bounds no solid, plan warns that the normals' side is the file's. Usage: plan_project.sh PROBECOMP CAD_FILE WORK_DIR SPACING
set -eu
P=$1; CAD=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
"$P" plan "$CAD" --spacing "$4" --output "$W/plan.csv" 2>"$W/plan.err"
# The model bounds no solid (the hammer's 45 surfaces): its normals' side is the file's, and plan says so.
if [ "$(basename "$CAD")" = gismo_hammer.iges ]; then
  grep -q '^probecomp: warning: 45 of the planned faces (0, ...) bound no closed solid' "$W/plan.err" ||
    { echo "FAIL: plan on an open model does not warn about its normals"; cat "$W/plan.err"; exit 1; }
fi
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
