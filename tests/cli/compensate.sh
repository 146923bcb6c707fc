#!/bin/sh
# End to end from the command line: the demo's files through compensate (CSV and DMIS) and fit; bad inputs give
# one line on standard error, a non-zero exit and no output file.
# Usage: compensate.sh PROBECOMP CAD_DIR WORK_DIR [light]
# light (the sanitizer build): the characteristics and the NIST parts' PMI are left to the Release run, which reads
# the same code paths through the unit tests there too (Characteristics.*, Pmi.*).
set -u
P=$1; CAD=$2; W=$3; LIGHT=${4:-}
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
"$P" demo --output-dir "$W/demo" >"$W/demo.txt" || { echo "FAIL: demo"; exit 1; }
check "grep -q 'CAD-based (probecomp)' '$W/demo.txt'" "demo prints the comparison"
for f in nominal.igs raw.csv compensated_cad.csv compensated_conventional.csv; do
  check "[ -s '$W/demo/$f' ]" "demo wrote $f"
done
N0="$W/demo/nominal.igs"
# Carried columns come back; every row in order.
awk -F, 'NR==1{print $0",id"; next} {print $0","NR-1}' "$W/demo/raw.csv" >"$W/raw_id.csv"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/raw_id.csv" --probe-radius 1 --output "$W/out.csv" \
  --json "$W/stats.json" --report "$W/report.html" --quiet || { echo "FAIL: compensate"; fail=1; }
check "[ \$(wc -l <'$W/out.csv') -eq \$(wc -l <'$W/raw_id.csv') ]" "one output row per input row"
check "head -1 '$W/out.csv' | grep -q '^x,y,z,nx,ny,nz,deviation,u,face,status,id$'" "output header"
check "tail -1 '$W/out.csv' | grep -q ',ok,7200$'" "last row carries its id"
S="$W/stats.json"
json_check "$S" "len(j['transform']) == 4 and all(len(row) == 4 for row in j['transform'])" "stats: a 4 x 4 transform"
json_check "$S" "j['registration']['converged'] is True and j['registration']['status'] == 'converged' and j['registration']['stop_reason']" \
  "stats: the registration converged, and why it stopped"
json_check "$S" "j['registration']['iterations'] > 0 and j['registration']['searches'] > 0 and j['registration']['scale'] > 0" \
  "stats: the registration's iterations, searches and scale"
json_check "$S" "[k for k in j['timings']] == ['read', 'prepare', 'register', 'fit', 'compensate', 'write', 'total'] and all(v >= 0 for v in j['timings'].values())" \
  "stats: every timing"
json_check "$S" "j['deviation']['points'] == 7200 and j['counts']['ok'] == 7200 and j['counts']['total'] == 7200" "stats: 7200 ok rows"
# The face holds every point and its side was decided from them: never "no-points".
json_check "$S" "[(f['points'], f['fitted'], f['material_side']) for f in j['faces']] == [(7200, True, 'approach-normals')]" \
  "face's material side from the approach normals"
json_check "$S" "all(f['control_points'] > 0 and f['noise_estimate'] > 0 and f['counts']['ok'] == 7200 for f in j['faces'])" \
  "stats: the face's fit and counts"
check "grep -q '<table' '$W/report.html'" "report written"
json_check "$S" "j['warnings'] == []" "no warnings on clean data"
# A reading recorded twice (720 rows copied after the file): fitted once, said on standard error and in the JSON,
# and every copy comes back exactly as its original.
{ cat "$W/raw_id.csv"; sed -n '2,721p' "$W/raw_id.csv"; } >"$W/repeated.csv"
"$P" compensate --cad "$N0" --points "$W/repeated.csv" --probe-radius 1 --output "$W/repeated_out.csv" \
  --json "$W/repeated.json" --quiet 2>"$W/repeated.err" || { echo "FAIL: compensate with repeated rows"; fail=1; }
check "grep -q '^probecomp: warning: 720 points repeat an earlier point' '$W/repeated.err'" "repeated rows: warning on standard error"
json_check "$W/repeated.json" "j['warnings'][0].startswith('720 points repeat')" "repeated rows: warning in the JSON"
json_check "$W/repeated.json" "j['faces'][0]['repeated_points'] == 720" "repeated rows: counted on the face"
check "[ \$(wc -l <'$W/repeated_out.csv') -eq 7921 ]" "repeated rows: every row back"
check "[ \"\$(sed -n '2,721p' '$W/repeated_out.csv')\" = \"\$(sed -n '7202,7921p' '$W/repeated_out.csv')\" ]" "repeated rows: copies come back as their originals"
# Units (issue 20, item 6): the same points in inches, with --units inch and the radius in inches, give the same
# results, written back in inches (x,y,z, deviation and u: 25.4 times smaller); --json stays in mm.
awk -F, 'BEGIN{OFS=","} NR==1{print; next} {$1=sprintf("%.15g",$1/25.4); $2=sprintf("%.15g",$2/25.4); $3=sprintf("%.15g",$3/25.4); print}' \
  "$W/raw_id.csv" >"$W/raw_inch.csv"
"$P" compensate --cad "$N0" --points "$W/raw_inch.csv" --units inch --probe-radius 0.0393700787401575 \
  --output "$W/out_inch.csv" --json "$W/inch.json" --quiet || { echo "FAIL: compensate --units inch"; fail=1; }
check "awk -F, 'NR==FNR{if(FNR>1){x[FNR]=\$1;y[FNR]=\$2;z[FNR]=\$3;d[FNR]=\$7;u[FNR]=\$8}; next}
  FNR>1{e=0; a=\$1*25.4-x[FNR]; if(a<0)a=-a; if(a>e)e=a; a=\$2*25.4-y[FNR]; if(a<0)a=-a; if(a>e)e=a;
  a=\$3*25.4-z[FNR]; if(a<0)a=-a; if(a>e)e=a; a=\$7*25.4-d[FNR]; if(a<0)a=-a; if(a>e)e=a;
  a=\$8*25.4-u[FNR]; if(a<0)a=-a; if(a>e)e=a; if(e>m)m=e} END{exit !(FNR==7201 && m<1e-6)}' '$W/out.csv' '$W/out_inch.csv'" \
  "inch input: every row equals the mm run's to 1e-6 mm, in inches"
json_check "$W/inch.json" "(j['inputs']['points_unit'], j['inputs']['probe_radius'], j['inputs']['tip_radii']) == ('inch', 1, [1])" \
  "inch input: the JSON names the unit and the radius in mm"
check "[ \"\$(json_value '$W/inch.json' \"j['deviation']\")\" = \"\$(json_value '$S' \"j['deviation']\")\" ]" \
  "inch input: JSON deviations in mm, as the mm run's"
"$P" compensate --cad "$N0" --points "$W/raw_inch.csv" --units inch --probe-radius 0.0393700787401575 \
  --output "$W/out_inch.dmo" --quiet || { echo "FAIL: compensate --units inch to DMIS"; fail=1; }
check "sed -n 4p '$W/out_inch.dmo' | grep -qx 'UNITS/INCH,ANGDEC'" "inch DMIS output states its unit"
expect_error "out_inch.dmo:4: the file says its lengths are in inch, not in mm" "$W/o.csv" \
  "$P" compensate --cad "$N0" --points "$W/out_inch.dmo" --units mm --probe-radius 1 --output "$W/o.csv"
# DMIS out, then DMIS in: the same points.
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/out.dmo" || fail=1
check "[ \$(grep -c '^FA(P' '$W/out.dmo') -eq 7200 ]" "DMIS output has every point"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/out.dmo" --probe-radius 0.001 --method conventional \
  --output "$W/again.csv" || { echo "FAIL: DMIS input"; fail=1; }
check "[ \$(wc -l <'$W/again.csv') -eq 7201 ]" "DMIS input read"
# Conventional: the demo's own conventional output is reproduced.
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" --probe-radius 1 --method conventional >"$W/conv.csv" || fail=1
check "[ \$(wc -l <'$W/conv.csv') -eq 7201 ]" "conventional to standard output"
# fit: the measured surface as IGES, readable again.
"$P" fit --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/actual.igs" --quiet || fail=1
check "'$P' info '$W/actual.igs' | grep -q 'total: 1 faces'" "fit wrote one NURBS face"
if [ "$LIGHT" != light ]; then
# --characteristics: a surface profile without datums on the demo's panel (its form after a best fit of its own
# points: the dent and bulge, about 2 mm wide a zone), judged with U = 2u. With the panel itself as datum A (least
# squares: it fixes all six motions), the same points in that frame are the same best fit: the same value, and a u
# with the datum's share added. With the panel as a tangent datum B, every point lies on the material side of it and
# the deepest as shallow as can be: max <= 0, and the deepest no deeper than the least-squares frame's zone is wide
# (that frame moved out to touch would be a tangent one). pmi on an IGES file, refused.
printf '{"datums": {"A": {"faces": [0]}, "B": {"faces": [0], "fit": "tangent"}}, "characteristics": [
  {"name": "P1", "faces": [0], "tolerance": 3.0}, {"name": "P2", "faces": [0], "tolerance": 0.001},
  {"name": "P3", "faces": [0], "tolerance": 3.0, "datums": ["A"]}, {"name": "P4", "faces": [0], "tolerance": 3.0, "datums": ["B"]}]}' >"$W/spec.json"
"$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 --characteristics "$W/spec.json" \
  --output "$W/spec.csv" --json "$W/spec_stats.json" --quiet 2>"$W/spec.err" || { echo "FAIL: --characteristics"; fail=1; }
json_check "$W/spec_stats.json" "[c['decision'] for c in j['characteristics']][:3] == ['conforms', 'does-not-conform', 'conforms']" \
  "--characteristics: a wide zone conforms, a 1 um one does not, in datum A's frame it conforms" || fail=1
json_check "$W/spec_stats.json" "j['characteristics'][3]['decision'] != 'not-evaluated' and j['characteristics'][3]['max'] <= 1e-6 and -j['characteristics'][3]['min'] <= j['characteristics'][0]['max'] - j['characteristics'][0]['min']" \
  "--characteristics: in the frame of the panel as a tangent datum, every point inside the material" || fail=1
json_check "$W/spec_stats.json" "abs(j['characteristics'][0]['value'] - 2 * max(-j['characteristics'][0]['min'], j['characteristics'][0]['max'])) < 1e-6 and j['characteristics'][0]['points'] == 7200" \
  "--characteristics: the profile's value, the centred zone holding all 7 200 points" || fail=1
json_check "$W/spec_stats.json" "abs(j['characteristics'][2]['value'] - j['characteristics'][0]['value']) < 1e-6 and j['characteristics'][2]['u'] > j['characteristics'][0]['u']" \
  "--characteristics: in the frame of the panel as datum, the same value and a larger u" || fail=1
json_check "$W/spec_stats.json" "[(d['name'], d['frame'], d['fit'], d['fixes'], d['points']) for d in j['datums']] == [('A', 'A', 'least-squares', 6, 7200), ('B', 'B', 'tangent', 6, 7200)]" \
  "--characteristics: the datums fitted, in --json" || fail=1
# (P4's frame rests on the few points the panel touches it at, so points far from them carry a large share of its
# uncertainty: conforms or indeterminate, as its U says.)
check "grep -q 'probecomp: P3: conforms (value' '$W/spec.err' && grep -Eq 'probecomp: P4: (conforms|indeterminate) \(value' '$W/spec.err'" \
  "--characteristics: the decisions on standard error"
# --replan: a zone exactly the profile's value leaves it indeterminate (its extreme points' d ± U cross the limit);
# the program measures those points again, at their contacts along their normals, and reads back as DMIS.
python3 -c "import json; v = json.load(open('$W/spec_stats.json'))['characteristics'][0]['value']; print('{\"characteristics\": [{\"name\": \"L\", \"faces\": [0], \"tolerance\": %r}]}' % v)" >"$W/limit.json"
"$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 --characteristics "$W/limit.json" \
  --replan "$W/replan.dmi" --output "$W/limit.csv" --quiet 2>"$W/limit.err" || { echo "FAIL: --replan"; fail=1; }
check "grep -q 'probecomp: L: indeterminate' '$W/limit.err' && [ \$(grep -c '^PTMEAS/CART,' '$W/replan.dmi') -ge 1 ] && tail -1 '$W/replan.dmi' | grep -q ENDFIL" \
  "--replan: the indeterminate profile's undecided points, as PTMEAS"
"$P" convert "$W/replan.dmi" "$W/replan.csv" || fail=1
check "[ \$((\$(wc -l <'$W/replan.csv') - 1)) -eq \$(grep -c '^PTMEAS/CART,' '$W/replan.dmi') ]" "--replan: the program reads back, one point per PTMEAS"
expect_error "--replan must end in .dmi" "$W/r.txt" "$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 \
  --characteristics "$W/limit.json" --replan "$W/r.txt" --output "$W/r.csv"
expect_error "--replan needs --characteristics" "$W/r.dmi" "$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 \
  --replan "$W/r.dmi" --output "$W/r.csv"
# alignment: the whole output in datum A's frame (the panel's least-squares fit): its deviations are that frame's.
sed 's/"characteristics"/"alignment": ["A"], "characteristics"/' "$W/spec.json" >"$W/aligned.json"
"$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 --characteristics "$W/aligned.json" \
  --output "$W/aligned.csv" --json "$W/aligned_stats.json" --report "$W/aligned.html" --quiet 2>/dev/null || { echo "FAIL: alignment"; fail=1; }
check "grep -q 'id=\"characteristics\"' '$W/aligned.html' && grep -q 'in datum frame A.' '$W/aligned.html'" "alignment: the report's characteristics table, and its frame"
json_check "$W/aligned_stats.json" "j['alignment'] == {'frame': 'A', 'fixed': 6} and abs(j['deviation']['max'] - j['characteristics'][2]['max']) < 1e-6 and abs(j['deviation']['min'] - j['characteristics'][2]['min']) < 1e-6" \
  "alignment: the deviation column in datum A's frame, its extremes those of the profile in that frame" || fail=1
expect_error "no semantic PMI" "$W/pmi.csv" "$P" compensate --cad "$N0" --points "$W/demo/raw.csv" --probe-radius 1 --characteristics pmi --output "$W/pmi.csv"
# info: a STEP AP242 file's semantic PMI; magnitudes OpenCASCADE does not read are named, not printed as 0.
"$P" info "$CAD/nist_ftc_06_asme1_ap242-e2.stp" --json >"$W/ftc06.json" 2>"$W/ftc06.err" || { echo "FAIL: info ftc06"; fail=1; }
json_check "$W/ftc06.json" "len(j['pmi']['tolerances']) == 27 and all(t['value'] > 0 for t in j['pmi']['tolerances'])" \
  "info --json lists FTC-06's 27 tolerances with their magnitudes" || fail=1
json_check "$W/ftc06.json" "sum(t['type'] == 'profile of surface' for t in j['pmi']['tolerances']) == 11" \
  "info --json: FTC-06's 11 surface profiles" || fail=1
# CTC-02's magnitudes, which OpenCASCADE reads as 0, from the file's own text (three unequal zones, 0, 0.5 and 2.5 mm
# of 2.5 outside, as the file states them), and its point datum targets A1-A3, B1-B4 and C1 on the faces they lie on.
"$P" info "$CAD/nist_ctc_02_asme1_ap242-e2.stp" --json >"$W/ctc02.json" 2>"$W/ctc02.err" || { echo "FAIL: info ctc02"; fail=1; }
json_check "$W/ctc02.json" "len(j['pmi']['tolerances']) == 22 and all(t['value'] > 0 for t in j['pmi']['tolerances']) and sorted(t['outside'] for t in j['pmi']['tolerances'] if 'outside' in t) == [0, 0.5, 2.5]" \
  "info --json: CTC-02's 22 magnitudes and its 3 unequal zones, read from the file's text" || fail=1
json_check "$W/ctc02.json" "{d['name']: len(d['point_targets']) for d in j['pmi']['datum_features'] if d['point_targets']} == {'A': 3, 'B': 4, 'C': 1} and all(t['face'] >= 0 for d in j['pmi']['datum_features'] for t in d['point_targets']) and all(d['line_targets'] == [] for d in j['pmi']['datum_features'])" \
  "info --json: CTC-02's point datum targets on their faces, and no line targets" || fail=1
check "! grep -q 'its magnitude was not read' '$W/ctc02.err'" "no magnitude left unread"
fi

N="$W/demo/nominal.igs"
printf 'x,y,z\n1,2,3\n4,nan,6\n' >"$W/nan.csv"
printf 'x,y,z\n' >"$W/empty.csv"
printf 'x,y,z\n1000,1000,1000\n1001,1000,1000\n1000,1001,1000\n' >"$W/far.csv"
cut -d, -f1-3 "$W/demo/raw.csv" >"$W/no_ijk.csv"
printf 'ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((%s),%s);\nFILE_NAME(%s,%s,(%s),(%s),%s,%s,%s);\nFILE_SCHEMA((%s));\nENDSEC;\nDATA;\n#1=CARTESIAN_POINT(%s,(0.,0.,0.));\nENDSEC;\nEND-ISO-10303-21;\n' \
  "''" "'2;1'" "'p.stp'" "''" "''" "''" "''" "''" "''" "'CONFIG_CONTROL_DESIGN'" "''" >"$W/no_surfaces.stp"
expect_error "probe-radius" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/demo/raw.csv" --probe-radius 0 --output "$W/o.csv"
expect_error "probe-radius" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/demo/raw.csv" --probe-radius -1 --output "$W/o.csv"
expect_error "missing.csv" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/missing.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "missing.igs" "$W/o.csv" "$P" compensate --cad "$W/missing.igs" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "nan.csv:3" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/nan.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "no points" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/empty.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "nowhere near" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/far.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "no_surfaces.stp" "$W/o.csv" "$P" compensate --cad "$W/no_surfaces.stp" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "i,j,k" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/no_ijk.csv" --probe-radius 1 --method conventional --output "$W/o.csv"
expect_error ".igs, .iges" "$W/a.txt" "$P" fit --cad "$N" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/a.txt"
# The exit status says what kind of failure it was (docs/cli.md, "Exit status").
check "[ \$(status_of '$P' compensate --cad '$N' --points '$W/demo/raw.csv' --probe-radius 0) -eq 2 ]" "exit 2: an option's value"
check "[ \$(status_of '$P' compensate --cad '$N' --points '$W/nan.csv' --probe-radius 1) -eq 3 ]" "exit 3: bad points"
check "[ \$(status_of '$P' compensate --cad '$N' --points '$W/far.csv' --probe-radius 1) -eq 3 ]" "exit 3: points nowhere near"
check "[ \$(status_of '$P' compensate --cad '$W/missing.igs' --points '$W/demo/raw.csv' --probe-radius 1) -eq 4 ]" "exit 4: CAD file"
printf 'x,y,z\n10,10,1\n20,10,1\n10,20,1\n' >"$W/three.csv"
check "[ \$(status_of '$P' compensate --cad '$N' --points '$W/three.csv' --probe-radius 1) -eq 5 ]" "exit 5: registration"

# CSV as a spreadsheet set to a decimal comma writes it (issue 20, item 8): a byte-order mark, a quoted header,
# ';' between fields, decimal commas, CRLF. The same points, so the same result, number for number.
awk -F, 'NR == 1 { printf "\357\273\277\"x\";\"y\";\"z\";\"i\";\"j\";\"k\"\r\n"; next }
         { for (f = 1; f <= NF; f++) { gsub(/\./, ",", $f); printf "%s%s", $f, (f < NF ? ";" : "\r\n") } }' \
  "$W/demo/raw.csv" >"$W/excel.csv"
"$P" compensate --cad "$N" --points "$W/excel.csv" --probe-radius 1 --output "$W/excel_out.csv" --quiet ||
  { echo "FAIL: compensate on the spreadsheet's CSV"; fail=1; }
"$P" compensate --cad "$N" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/plain_out.csv" --quiet
check "cmp -s '$W/excel_out.csv' '$W/plain_out.csv'" "the spreadsheet's CSV gives the same output"

# Degenerate point sets are refused with the reason (issue 20, item 10): 500 identical points, 200 on a line
# across the panel. (Before: the identical points came back "ok" with u = 0.1 um.)
awk 'BEGIN { print "x,y,z"; for (i = 0; i < 500; i++) print "10,5,3.2" }' >"$W/identical.csv"
awk 'BEGIN { print "x,y,z"; for (i = 0; i < 200; i++) printf "%.3f,%.3f,3\n", -40 + 0.4 * i, 0.1 * i - 10 }' >"$W/line.csv"
expect_error "all 500 points are at one position" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/identical.csv" --probe-radius 1 --output "$W/o.csv"
expect_error "lie on one line" "$W/o.csv" "$P" compensate --cad "$N" --points "$W/line.csv" --probe-radius 1 --output "$W/o.csv"
check "[ \$(status_of '$P' compensate --cad '$N' --points '$W/identical.csv' --probe-radius 1) -eq 3 ]" "exit 3: identical points"

# A measurement is never overwritten (issue 20, item 10): an output naming an input, by its own path, another
# path or a link, is refused before anything runs, and the input is unchanged byte for byte.
cp "$W/demo/raw.csv" "$W/keep.csv"; cp "$W/demo/raw.csv" "$W/keep.orig"; ln -sf keep.csv "$W/keep_link.csv"
expect_error "is the --points file" "" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 --output "$W/keep.csv"
expect_error "is the --points file" "" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 --output "$W/./keep.csv"
expect_error "is the --points file" "" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 --output "$W/keep_link.csv"
expect_error "is the --points file" "" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 --json "$W/keep.csv"
expect_error "is the --cad file" "" "$P" fit --cad "$N" --points "$W/keep.csv" --probe-radius 1 --output "$N"
expect_error "name the same file" "$W/same.csv" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 --output "$W/same.csv" --json "$W/same.csv"
expect_error "is the --points file" "" "$P" project --cad "$N" --points "$W/keep.csv" --output "$W/keep.csv"
check "cmp -s '$W/keep.csv' '$W/keep.orig'" "the measurement is unchanged"
# All outputs or none: a --json that cannot be written leaves neither the CSV nor the report behind.
expect_error "cannot be written" "$W/late.csv" "$P" compensate --cad "$N" --points "$W/keep.csv" --probe-radius 1 \
  --output "$W/late.csv" --report "$W/late.html" --json "$W/no_such_dir/late.json" --quiet
check "[ ! -e '$W/late.html' ] && [ ! -e '$W/late.partial.html' ]" "no report left behind when the JSON fails"
exit $fail
