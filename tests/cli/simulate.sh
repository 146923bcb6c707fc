#!/bin/sh
# probecomp simulate end to end: a plan from --spacing and one from --plan, with a misalignment, a bump and a
# sine; raw.csv, truth.csv and actual.igs written with the promised columns and rows; compensate runs on the
# result; bad inputs fail with one line and leave no file. Usage: simulate.sh PROBECOMP CAD_DIR WORK_DIR [light]
# light (the sanitizer build): not the crease, twist and banded wave, whose surface fits take half a minute there and
# which Deformation.* run through the sanitizers too; the first case at a coarser spacing.
set -u
P=$1; CAD=$2/asitus_wavy-cube.stp; W=$3; LIGHT=${4:-}
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"

# (Light: a 0.1 mm spacing, a quarter of the touches.)
if [ "$LIGHT" = light ]; then SPACING=0.1; TOUCHES=300; else SPACING=0.05; TOUCHES=1000; fi
"$P" simulate --cad "$CAD" --faces 2,3,5 --spacing $SPACING --probe-radius 0.1 --misalign 0.002,0,0.001,0.1,0,0.2 \
  --deform bump:0.5,0.5,1,0.01,0.1 --deform sine:0.002,0.3,1,0,0 --noise 0.0005 --seed 3 --output-dir "$W/a" >"$W/a.txt" \
  || { echo "FAIL: simulate --spacing"; cat "$W/a.txt"; exit 1; }
head -1 "$W/a/raw.csv" | grep -qx 'x,y,z,i,j,k,point' || { echo "FAIL: raw.csv header"; head -1 "$W/a/raw.csv"; fail=1; }
head -1 "$W/a/truth.csv" | grep -qx 'point,status,x,y,z,nx,ny,nz,cx,cy,cz,face,u,v,travel' || { echo "FAIL: truth.csv header"; fail=1; }
programmed=$(sed -n 's/^probecomp simulate: \([0-9]*\) programmed points, \([0-9]*\) touched.*/\1/p' "$W/a.txt")
touched=$(sed -n 's/^probecomp simulate: \([0-9]*\) programmed points, \([0-9]*\) touched.*/\2/p' "$W/a.txt")
[ "$(($(wc -l <"$W/a/truth.csv") - 1))" -eq "$programmed" ] || { echo "FAIL: truth.csv rows != $programmed programmed"; fail=1; }
[ "$(($(wc -l <"$W/a/raw.csv") - 1))" -eq "$touched" ] || { echo "FAIL: raw.csv rows != $touched touched"; fail=1; }
[ "$touched" -gt $TOUCHES ] || { echo "FAIL: only $touched touches"; fail=1; }
"$P" info "$W/a/actual.igs" | grep -q '^total: 6 faces' || { echo "FAIL: actual.igs does not hold the cube's 6 faces"; fail=1; }
"$P" compensate --cad "$CAD" --points "$W/a/raw.csv" --probe-radius 0.1 --output "$W/a/out.csv" --quiet \
  || { echo "FAIL: compensate on the simulated points"; fail=1; }
[ "$(wc -l <"$W/a/out.csv")" -eq "$(wc -l <"$W/a/raw.csv")" ] || { echo "FAIL: compensate rows"; fail=1; }
head -1 "$W/a/out.csv" | grep -q ',point$' || { echo "FAIL: the point column is not carried"; fail=1; }

# The same measurement from a plan file, without noise: every centre is on its programmed line.
"$P" plan "$CAD" --faces 2 --spacing 0.1 --output "$W/plan.csv"
"$P" simulate --cad "$CAD" --plan "$W/plan.csv" --probe-radius 0.1 --misalign 0,0,0.003,0,0,0 --output-dir "$W/b" >/dev/null \
  || { echo "FAIL: simulate --plan"; fail=1; }
paste -d, "$W/plan.csv" "$W/b/raw.csv" | awk -F, 'NR > 1 {
    dx = $8 - $1; dy = $9 - $2; dz = $10 - $3;
    cx = dy * $6 - dz * $5; cy = dz * $4 - dx * $6; cz = dx * $5 - dy * $4;
    off = sqrt(cx * cx + cy * cy + cz * cz); if (off > 2e-9) { print "FAIL: row " NR " is " off " mm off its line"; bad = 1 } }
  END { exit bad }' || fail=1

# Creases, twists and banded waves are accepted and simulated.
if [ "$LIGHT" != light ]; then
  "$P" simulate --cad "$CAD" --faces 2 --spacing 0.1 --probe-radius 0.1 --deform crease:0.5,0.5,0,1,1,0,0.005,0.1 \
    --deform twist:0.5,0.5,0,1,0,0,0,1,0,0.003,0.5 --deform sine:0.002,0.3,1,0,0,0.5,0.5,0,0.1,0,0,1,0 \
    --output-dir "$W/c" >"$W/c.txt" || { echo "FAIL: simulate with a crease, a twist and a banded wave"; cat "$W/c.txt"; fail=1; }
  grep -q ' 0 missed' "$W/c.txt" || { echo "FAIL: creased, twisted face missed"; cat "$W/c.txt"; fail=1; }
fi

B="$W/bad"
expect_error 'bump:X,Y,Z,A,W' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --deform bump:1,2,3 --output-dir "$B"
expect_error "is none of bump" "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --deform blob:1 --output-dir "$B"
expect_error 'crease:OX,OY,OZ,DX,DY,DZ,H,W: the width W must be positive' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --deform crease:0,0,0,1,0,0,0.1,0 --output-dir "$B"
expect_error 'twist:OX,OY,OZ,D1X,D1Y,D1Z,D2X,D2Y,D2Z,A,L: needs 11 numbers' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --deform twist:0,0,0,1,0,0 --output-dir "$B"
expect_error 'a band needs a window W > 0' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --deform sine:0.01,8,1,0,0,0,0,0,0,0,0,1,0 --output-dir "$B"
expect_error 'needs 6 numbers' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --misalign 1,2 --output-dir "$B"
expect_error '--pretravel P0,B,A.*: needs 3 to 5 numbers, got 2' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --pretravel 0.002,0.003 --output-dir "$B"
expect_error '--pretravel P0,B,A.*: the lobe count N must be a positive whole number, not 2.5' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0.1 --pretravel 0.002,0.003,0.004,2.5 --output-dir "$B"
expect_error 'probe-radius' "$B/raw.csv" "$P" simulate --cad "$CAD" --spacing 0.1 --probe-radius 0 --output-dir "$B"
expect_error '--plan PLAN.csv or --spacing' "$B/raw.csv" "$P" simulate --cad "$CAD" --probe-radius 0.1 --output-dir "$B"
printf 'x,y,z\n0,0,0\n' >"$W/noijk.csv"
expect_error 'needs i,j,k' "$B/raw.csv" "$P" simulate --cad "$CAD" --plan "$W/noijk.csv" --probe-radius 0.1 --output-dir "$B"
expect_error 'no programmed point touches' "$B/raw.csv" "$P" simulate --cad "$CAD" --plan "$W/plan.csv" --probe-radius 0.1 --misalign 50,0,0,0,0,0 --output-dir "$B"
[ $fail -eq 0 ] && echo "simulate: files, rows, line check, compensate round trip and 12 bad inputs as promised; creases, twists and banded waves"
exit $fail
