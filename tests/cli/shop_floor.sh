#!/bin/sh
# Issue 20 on real CAD samples with points from `probecomp simulate`, scored against the simulator's truth
# (score.awk: (compensated − true contact)·actual normal, by status): points on some faces of a multi-face part,
# a rough alignment several mm and ~10° off, one beyond reach of the coarse alignment (refused, then done with
# --initial-transform), and points that fix only some motions (reported).
# Usage: shop_floor.sh PROBECOMP CAD_DIR WORK_DIR [light]
# light (the sanitizer build, about twenty times slower): the cases but the partial coverage, the rough alignment, the
# impeller and surf128 (the material side decided from the data: MaterialSide.* there), on fewer points (20 faces at a
# 3 mm spacing), for memory and undefined behaviour; the figures and outcomes, which depend on the points, are held by
# the Release run.
set -u
P=$1; CAD=$2; W=$3; LIGHT=${4:-}
if [ "$LIGHT" = light ]; then FACES=0-20; SPACING=3; else FACES=0-40; SPACING=2; fi
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
# check_result CONDITION DESCRIPTION and json_check_result FILE CONDITION DESCRIPTION: as check and json_check,
# but not in the light run.
check_result() { [ "$LIGHT" = light ] || check "$@"; }
json_check_result() { [ "$LIGHT" = light ] || json_check "$@"; }
SCORE="$(dirname "$0")/score.awk"
HPDC="$CAD/asitus_repatch-hpdc.stp"
# ok_within DIR STD_UM MAX_UM: the ok rows' error std (µm) within its bound, and at least 40 % of the rows ok. The
# largest |error| within MAX_UM on the faces fitted as NURBS, whose rows are smoothed; on the faces too sparse for
# that, fitted as the plane, cylinder, cone, sphere or torus they are (the JSON's `fitted_as`), within 4 u: those
# rows keep each touch's own noise (σ = 2 µm here), so among a few hundred one is 6–7 µm off. The rest: edges, and
# faces with too few points for either fit. Prints the scores when not.
ok_within() {
  awk -F, -f "$SCORE" "$1/truth.csv" "$1/out.csv" >"$1/score.txt"
  rows=$(($(wc -l <"$1/out.csv") - 1))
  awk -v s="$2" -v rows="$rows" '$1 == "ok:" { ok = 1; if ($2 < 0.4 * rows || $7 > s) bad = 1 }
    END { exit !(ok && !bad) }' "$1/score.txt" || { cat "$1/score.txt"; return 1; }
  elements=$(python3 -c 'import json, sys; print(" ".join(str(f["face"]) for f in json.load(open(sys.argv[1]))["faces"] if f.get("fitted_as")))' "$1/out.json")
  awk -F, -v m="$3" -v elements="$elements" '
    NR == FNR { if (FNR > 1) { x[$1] = $3; y[$1] = $4; z[$1] = $5; n1[$1] = $6; n2[$1] = $7; n3[$1] = $8 }; next }
    FNR == 1 { split(elements, list, " "); for (i in list) element[list[i]] = 1; next }
    $10 == "ok" { p = $11; e = ($1 - x[p]) * n1[p] + ($2 - y[p]) * n2[p] + ($3 - z[p]) * n3[p]; e = e < 0 ? -e : e
      if (($9 in element) ? e > 4 * $8 : 1000 * e > m) { printf "row %s (face %s): error %.2f um, u %.2f um\n", p, $9, 1000 * e, 1000 * $8; bad = 1 } }
    END { exit bad }' "$1/truth.csv" "$1/out.csv" || { cat "$1/score.txt"; return 1; }
}
# rows_within DIR STATUS STD_UM MAX_UM: that status's rows (scored by ok_within before) within the bounds.
rows_within() {
  awk -v st="$2:" -v s="$3" -v m="$4" '$1 == st { found = 1; if ($7 > s || $9 > m) bad = 1 } END { exit !(found && !bad) }' \
    "$1/score.txt" || { cat "$1/score.txt"; return 1; }
}
# within_u DIR K: every ok and outlier row's error within K times its u. Prints the rows beyond when not.
within_u() {
  awk -F, -v k="$2" 'NR == FNR { if (FNR > 1) { x[$1] = $3; y[$1] = $4; z[$1] = $5; n1[$1] = $6; n2[$1] = $7; n3[$1] = $8 }; next }
    FNR > 1 && ($10 == "ok" || $10 == "outlier") { p = $11; e = ($1 - x[p]) * n1[p] + ($2 - y[p]) * n2[p] + ($3 - z[p]) * n3[p]
      if ((e < 0 ? -e : e) > k * $8) { printf "row %s (%s): error %.1f um, u %.1f um\n", p, $10, 1000 * e, 1000 * $8; bad = 1 } }
    END { exit bad }' "$1/truth.csv" "$1/out.csv"
}
simulate() {  # DIR MISALIGN
  "$P" simulate --cad "$HPDC" --spacing $SPACING --faces $FACES --probe-radius 1 --misalign "$2" --noise 0.002 --seed 3 \
    --output-dir "$1" >/dev/null || { echo "FAIL: simulate $2"; fail=1; }
}

# 1. Points on 41 of the die-cast part's 232 faces, 0.3 mm and 1° off: registered to the faces they touch.
# (Not in the light run, where its checks are not made: the 3 mm stylus below runs the same code on the same faces.)
if [ "$LIGHT" != light ]; then
  simulate "$W/partial" 0.3,0.2,-0.1,1,0.5,0
  "$P" compensate --cad "$HPDC" --points "$W/partial/raw.csv" --probe-radius 1 --output "$W/partial/out.csv" \
    --json "$W/partial/out.json" --quiet 2>"$W/partial/err" || { echo "FAIL: partial coverage"; fail=1; }
  check_result "ok_within '$W/partial' 1 5" "partial coverage: ok rows within std 1 um, max 5 um of the truth"
  # Item 4: tips that touched a face's edge, offset towards it, and the faces too small for a fit, offset along the
  # nominal normal. Before trims were closed across their pcurves' gaps (a phantom face beyond the trim along a
  # domain edge), edge rows had std 26 um, max 220 um here.
  check_result "rows_within '$W/partial' edge 4 12" "partial coverage: edge rows within std 4 um, max 12 um"
  check_result "rows_within '$W/partial' few-points 4 12" "partial coverage: few-points rows within std 4 um, max 12 um"
  json_check_result "$W/partial/out.json" "j['registration']['starts'] == 1" "partial coverage: registered from the given start"
  # Faces too small for their points' control net say so, with what they would need (issue 20, item 5).
  check_result "grep -q 'warning: [0-9]* faces with points were not fitted; .*: face [0-9]*, [0-9]* points off the edges for [0-9]* control points ([0-9]* needed)' '$W/partial/err'" \
    "partial coverage: unfitted faces and why on standard error"
  json_check_result "$W/partial/out.json" \
    "any(not f['fitted'] and f['counts']['ok'] == 0 and f['counts']['outlier'] == 0 and f['counts']['few-points'] > 0 and f['stop_reason'].startswith('not fitted: ') and 'points off the edges for' in f['stop_reason'] for f in j['faces'])" \
    "partial coverage: an unfitted face's counts by status and its reason in the JSON"
fi

# Item 4 with a 3 mm stylus, whose tip cannot reach into the part's 2 mm fillets: it sits against both walls
# there (double-contact), and many touches land on edges. Every such row is compensated from the nominal part's
# point nearest its registered centre. Before: edge rows std 95 um, max 997 um; the two tips against two walls
# came back `outlier`, 1.9-2.2 mm off.
"$P" simulate --cad "$HPDC" --spacing $SPACING --faces "$([ "$LIGHT" = light ] && echo 0-20 || echo 0-60)" --probe-radius 3 --misalign 0.3,0.2,-0.1,1,0.5,0 --noise 0.002 \
  --seed 3 --output-dir "$W/stylus3" >/dev/null || { echo "FAIL: simulate stylus3"; fail=1; }
"$P" compensate --cad "$HPDC" --points "$W/stylus3/raw.csv" --probe-radius 3 --output "$W/stylus3/out.csv" \
  --json "$W/stylus3/out.json" --quiet 2>/dev/null || { echo "FAIL: stylus3"; fail=1; }
check_result "ok_within '$W/stylus3' 1 8" "3 mm stylus: ok rows within std 1 um, max 8 um"
check_result "rows_within '$W/stylus3' edge 4 12" "3 mm stylus: edge rows within std 4 um, max 12 um"
check_result "rows_within '$W/stylus3' few-points 4 12" "3 mm stylus: few-points rows within std 4 um, max 12 um"
# The part is rigid, so a double contact's true deviation is zero on either face it touches.
check_result "awk -F, 'NR > 1 && \$10 == \"double-contact\" { n++; d = \$7 < 0 ? -\$7 : \$7; if (d > 0.005) bad = 1 } END { exit !(n >= 1 && !bad) }' '$W/stylus3/out.csv'" \
  "3 mm stylus: double-contact rows found, their deviations within 5 um of zero"
json_check_result "$W/stylus3/out.json" "j['counts']['double-contact'] > 0" "3 mm stylus: double-contact in the JSON's counts"

# 2. 1 mm and 10° off: ICP alone lands on the wrong side of the walls (29 % of the points r/2 inside the
# material); the coarse alignment finds the right pose, and says so.
if [ "$LIGHT" != light ]; then  # the coarse alignment runs in the light run too, for the far case
  simulate "$W/rough" 1,1,1,10,0,0
  "$P" compensate --cad "$HPDC" --points "$W/rough/raw.csv" --probe-radius 1 --output "$W/rough/out.csv" \
    --json "$W/rough/out.json" --quiet 2>"$W/rough/err" || { echo "FAIL: rough alignment"; fail=1; }
  check_result "ok_within '$W/rough' 1 5" "rough alignment: ok rows within std 1 um, max 5 um"
  check_result "grep -q 'warning: the registration from the given start was not credible.*coarse alignment' '$W/rough/err'" \
    "rough alignment: the coarse alignment is reported on standard error"
  json_check_result "$W/rough/out.json" "j['warnings'][0].startswith('the registration from the given start was not credible')" \
    "rough alignment: and in the JSON"
fi

# 3. 35° off about x: beyond the coarse alignment, which leaves the registration doubtful (18 % of the points r/2
# inside the material). Refused (exit 5, no output) naming both ways on: with a rough transform (30° about x) the
# run is right; --accept-doubtful-registration runs on, with a warning.
simulate "$W/far" 0,0,0,35,0,0
if [ "$LIGHT" = light ]; then
  rc=$(status_of "$P" compensate --cad "$HPDC" --points "$W/far/raw.csv" --probe-radius 1 --quiet)
  check "[ $rc -eq 0 ] || [ $rc -eq 5 ]" "far (light): done or refused, nothing else"
else
  expect_error "initial-transform" "$W/far/out.csv" \
    "$P" compensate --cad "$HPDC" --points "$W/far/raw.csv" --probe-radius 1 --output "$W/far/out.csv" --quiet
fi
# expect_error leaves the run's exit status in rc and its message in $W/stderr.
check_result "[ $rc -eq 5 ]" "far: exit 5"
check_result "grep -q 'doubtful.*--accept-doubtful-registration' '$W/stderr'" "far: the refusal names --accept-doubtful-registration"
printf '# 30 degrees about x\n1 0 0 0\n0 0.8660254037844387 -0.5 0\n0, 0.5, 0.8660254037844387, 0\n0 0 0 1\n' >"$W/far/T.txt"
"$P" compensate --cad "$HPDC" --points "$W/far/raw.csv" --probe-radius 1 --initial-transform "$W/far/T.txt" \
  --output "$W/far/out.csv" --json "$W/far/out.json" --quiet || { echo "FAIL: --initial-transform"; fail=1; }
check_result "ok_within '$W/far' 1 8" "far with --initial-transform: ok rows within std 1 um, max 8 um"
json_check_result "$W/far/out.json" "abs(j['transform'][1][1] - 0.8191520) < 1e-4" \
  "far: the registered rotation is 35 degrees (cos 0.8191520)"
[ "$LIGHT" = light ] || "$P" compensate --cad "$HPDC" --points "$W/far/raw.csv" --probe-radius 1 \
  --accept-doubtful-registration --output "$W/far/accepted.csv" --quiet 2>"$W/far/accepted.err" ||
  { echo "FAIL: --accept-doubtful-registration"; fail=1; }
check_result "grep -q 'warning: the registration is doubtful.*accepted as asked' '$W/far/accepted.err'" \
  "far with --accept-doubtful-registration: exit 0 and the doubt on standard error"
expect_error "T.txt" "$W/o.csv" "$P" compensate --cad "$HPDC" --points "$W/far/raw.csv" --probe-radius 1 \
  --initial-transform "$W/far/T.txt" --output "$W/far/T.txt"

# 4. Points on one plane (the wavy cube's bottom face) fix 3 of 6 motions: the other 3 are reported.
"$P" simulate --cad "$CAD/asitus_wavy-cube.stp" --spacing 0.05 --faces 0 --probe-radius 0.1 --noise 0.001 \
  --output-dir "$W/plane" >/dev/null || { echo "FAIL: simulate plane"; fail=1; }
"$P" compensate --cad "$CAD/asitus_wavy-cube.stp" --points "$W/plane/raw.csv" --probe-radius 0.1 \
  --output "$W/plane/out.csv" --json "$W/plane/out.json" --quiet 2>"$W/plane/err" || { echo "FAIL: plane"; fail=1; }
check "[ \$(grep -c 'warning: the points do not fix the part' '$W/plane/err') -eq 3 ]" "plane: three free motions on standard error"
json_check "$W/plane/out.json" "[m['kind'] for m in j['registration']['free_motions']] == ['translation', 'translation', 'rotation'] and abs(j['registration']['free_motions'][2]['axis'][2]) > 0.99999" \
  "plane: two translations and a rotation about the plane's normal (z) in the JSON"
# Item 7: a bump on the impeller, whose degree-5 blades have a knot of multiplicity 4 before a long span. Before,
# simulate failed ("the face has no normal somewhere"): the deformed surface's fit had fewer samples in that span
# than basis functions living there. Not in the light run: the deformed blades' fit takes a minute there, and
# simulate.sh's --deform cases take the same code through the sanitizers.
if [ "$LIGHT" != light ]; then
  "$P" simulate --cad "$CAD/pyiges_impeller.igs" --deform bump:0,0,30,0.1,10 --spacing 8 --probe-radius 1 --noise 0.002 \
    --output-dir "$W/impeller" >/dev/null || { echo "FAIL: simulate --deform bump on the impeller"; fail=1; }
  "$P" compensate --cad "$CAD/pyiges_impeller.igs" --points "$W/impeller/raw.csv" --probe-radius 1 \
    --output "$W/impeller/out.csv" --quiet 2>/dev/null || { echo "FAIL: compensate the impeller"; fail=1; }
  awk -F, -f "$SCORE" "$W/impeller/truth.csv" "$W/impeller/out.csv" >"$W/impeller/score.txt"
  check_result "rows_within '$W/impeller' ok 1 5" "impeller with a bump: ok rows within std 1 um, max 5 um"
  check_result "rows_within '$W/impeller' few-points 4 12" "impeller with a bump: few-points rows within std 4 um, max 12 um"
fi

# 5. plan on a closed solid: the material side is the solid's, nothing to warn about (item 7; the open model's
# warning is in plan_project.sh).
"$P" plan "$HPDC" --spacing 10 --faces 0-5 --output "$W/plan.csv" 2>"$W/plan.err" || { echo "FAIL: plan"; fail=1; }
check "[ ! -s '$W/plan.err' ]" "plan on a solid: no warning"
# 6. Issue 49: an open surface of four faces (the IGES example surf128), its part program on face 0, 1.2° and
# 0.3 mm off, the points without i,j,k. The faces' material sides come from the data: the centres near face 0's
# junction with face 3 voted before registration as the misalignment put them, and face 3 came back on its wrong
# side, its rows 2 mm off (at a 1.5 mm spacing, 298 of them ok). Registered, its centres lie inside the material: turned, and said so.
if [ "$LIGHT" != light ]; then
  S128="$CAD/iges_spec_surf128.igs"
  "$P" simulate --cad "$S128" --spacing 3 --faces 0 --probe-radius 1 --misalign 0.25,0.1,-0.2,1.2,0.8,0 --noise 0.003 \
    --seed 4 --output-dir "$W/s128" >/dev/null || { echo "FAIL: simulate surf128"; fail=1; }
  awk -F, 'BEGIN { OFS = "," } { print $1, $2, $3, $7 }' "$W/s128/raw.csv" >"$W/s128/raw_noijk.csv"
  "$P" compensate --cad "$S128" --points "$W/s128/raw_noijk.csv" --probe-radius 1 --output "$W/s128/out.csv" \
    2>"$W/s128/err" || { echo "FAIL: compensate surf128 without i,j,k"; fail=1; }
  awk -F, 'NR == 1 || $9 == 3' "$W/s128/out.csv" >"$W/s128/face3.csv"
  awk -F, -f "$SCORE" "$W/s128/truth.csv" "$W/s128/face3.csv" >"$W/s128/score.txt"
  check_result "rows_within '$W/s128' all 4 12" "surf128 without i,j,k: face 3's rows (few-points and edge at this spacing) within std 4 um, max 12 um"
  check "grep -q 'warning: face(s) 3 (median .* mm) turned to the other side after registration' '$W/s128/err'" \
    "surf128 without i,j,k: face 3 turned after registration, on standard error"
  # Face 0's narrow end bends tighter than the tip: its radius offset folds and is millimetres off there, and the
  # fit turned inside out (normals 150-170 degrees off): ok rows were 2 mm off at 34-90 um of u. Turned rows now say
  # so, in u and on standard error. And the rows offset from the nominal part's nearest point (edge, few-points,
  # double-contact) whose centre lay inside the material were put 2r away, on the far side of the centre: the
  # edge rows of face 2 were 2 mm off.
  awk -F, -f "$SCORE" "$W/s128/truth.csv" "$W/s128/out.csv" >"$W/s128/score.txt"
  check "within_u '$W/s128' 5" "surf128 without i,j,k: every ok and outlier row within 5 u of the truth"
  check "grep -q 'warning: face 0: at [0-9]* rows the fitted normal is turned up to' '$W/s128/err'" \
    "surf128 without i,j,k: face 0's turned normals on standard error"
  check "grep -q 'warning: face 0 bends tighter than the tip (a radius of .* mm at u .*): its radius offset folds over there and is up to .* mm off' '$W/s128/err'" \
    "surf128 without i,j,k: face 0's folded offset on standard error"
  check_result "rows_within '$W/s128' edge 4 12" "surf128 without i,j,k: edge rows within std 4 um, max 12 um"
fi
exit $fail
