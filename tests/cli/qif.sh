#!/bin/sh
# Issue 21: QIF 3.0 and DMIS tips from the command line. The real QIF sample converts to CSV with every point
# exact; csv -> qif -> csv, dmo -> qif -> dmo (two tips) and inch csv -> qif -> csv give every value back; the
# demo's points compensated from QIF give the CSV run's figures; every QIF file written validates against the
# QIF 3.0 schemas (xmllint: missing, the test fails); bad inputs give one line naming the file and line, a
# non-zero exit and no output.
# Usage: qif.sh PROBECOMP DATA_DIR WORK_DIR   (DATA_DIR: tests/data, with cad/ and qif3-xsd/)
set -u
P=$1; DATA=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
SAMPLE="$DATA/cad/qif_QIF_PTS_SAMPLE.QIF"
XSD="$DATA/qif3-xsd/QIFDocument.xsd"
command -v xmllint >/dev/null 2>&1 || { echo "FAIL: xmllint is missing (Debian libxml2-utils): QIF output cannot be validated"; exit 1; }
# validates FILE: the QIF 3.0 schemas accept it (xmllint warns that it cannot fetch the W3C signature schema: only
# signed documents need it).
validates() {
  if ! xmllint --nonet --noout --schema "$XSD" "$1" >"$W/xmllint.log" 2>&1; then
    echo "FAIL: $1 does not validate against the QIF 3.0 schemas:"; grep -v 'xmldsig\|failed to load' "$W/xmllint.log" | head -5
    fail=1
  fi
}
# same_numbers A B COLUMNS: the CSV files have the same rows, and the named columns (1-based) hold the same numbers
# (awk reads them with strtod: the same text or another text of the same double).
same_numbers() {
  awk -F, -v cols="$3" 'BEGIN { n = split(cols, c, " ") } NR == FNR { a[FNR] = $0; rows = FNR; next }
    { split(a[FNR], x, ","); for (i = 1; i <= n; ++i) if (FNR > 1 && x[c[i]] + 0 != $c[i] + 0) bad++ }
    END { exit !(FNR == rows && !bad) }' "$1" "$2"
}

# The real sample: 691 points in 12 sets, each x,y,z exactly as the file writes it.
"$P" convert "$SAMPLE" "$W/sample.csv" || { echo "FAIL: convert the sample to CSV"; fail=1; }
check "[ \$(grep -vc '^#' '$W/sample.csv') -eq 692 ] && head -1 '$W/sample.csv' | grep -qx 'x,y,z,r,set'" "sample: 691 rows x,y,z,r,set"
check "[ \$(cut -d, -f5 '$W/sample.csv' | sed 1d | uniq | wc -l) -eq 12 ]" "sample: 12 sets"
check "[ \$(cut -d, -f4 '$W/sample.csv' | sed 1d | sort -u) = 2.49978271104 ]" "sample: every row's r is 2.49978271104"
xmllint --xpath "//*[local-name()='MeasuredPointSet']/*[local-name()='Points']/text()" "$SAMPLE" | tr -s ' \n' '\n\n' |
  grep . >"$W/sample_tokens.txt"
check "[ \$(wc -l <'$W/sample_tokens.txt') -eq 2073 ]" "sample: 2073 coordinates in the file"
check "sed 1d '$W/sample.csv' | cut -d, -f1-3 | tr ',' '\n' | paste -d' ' - '$W/sample_tokens.txt' |
  awk '\$1 + 0 != \$2 + 0 { bad++ } END { exit !(NR == 2073 && !bad) }'" "sample: every coordinate equals the file's"
"$P" convert "$SAMPLE" "$W/sample.qif" && validates "$W/sample.qif" || fail=1
"$P" convert "$SAMPLE" "$W/sample.dmo" || fail=1
check "[ \$(grep -c '^FA(' '$W/sample.dmo') -eq 691 ] && [ \$(grep -c '^SNSLCT' '$W/sample.dmo') -eq 1 ]" "sample to DMIS: 691 points, one tip"
"$P" convert "$W/sample.dmo" "$W/sample2.csv" || fail=1
check "same_numbers '$W/sample.csv' '$W/sample2.csv' '1 2 3 4'" "sample -> dmo -> csv: every x, y, z, r"

# csv -> qif -> csv: every value; the QIF of the QIF's CSV is the same file, byte for byte.
printf 'x,y,z,i,j,k,r,id\n0.1,-123.456789012345678,1e-7,0,0,2,0.5,a\n3.14159265358979,2.718281828459045,7,0.6,0.8,0,,b\n1e300,-1e-300,5,1,1,1,1.25,"c, d"\n' >"$W/rt.csv"
"$P" convert "$W/rt.csv" "$W/rt.qif" && validates "$W/rt.qif" || fail=1
"$P" convert "$W/rt.qif" "$W/rt2.csv" || fail=1
check "head -1 '$W/rt2.csv' | grep -qx 'x,y,z,i,j,k,r,set,id'" "csv -> qif -> csv: columns"
check "same_numbers '$W/rt.csv' '$W/rt2.csv' '1 2 3 4 5 6 7'" "csv -> qif -> csv: every value"
check "[ \"\$(cut -d, -f9- '$W/rt2.csv' | sed 1d)\" = \"\$(printf 'a\nb\n\"c, d\"')\" ]" "csv -> qif -> csv: the carried column"
"$P" convert "$W/rt2.csv" "$W/rt3.qif" || fail=1
check "cmp -s '$W/rt.qif' '$W/rt3.qif'" "csv -> qif -> csv -> qif: the same QIF"

# Inches: the unit goes with the points, both ways.
printf 'x,y,z,r\n1,-0.1,0.005,0.0393700787401575\n2.5,3,4,0.02\n' >"$W/inch.csv"
"$P" convert "$W/inch.csv" "$W/inch.qif" --units inch && validates "$W/inch.qif" || fail=1
check "grep -q '<UnitName>inch</UnitName>' '$W/inch.qif'" "inch csv -> qif: FileUnits inch"
"$P" convert "$W/inch.qif" "$W/inch2.csv" || fail=1
check "head -1 '$W/inch2.csv' | grep -qx '# lengths in inch'" "inch qif -> csv: says its unit"
check "grep -v '^#' '$W/inch2.csv' | same_numbers '$W/inch.csv' - '1 2 3 4'" "inch csv -> qif -> csv: every value"
expect_error "inch2.csv:1: the file says its lengths are in inch, not in mm" "$W/inch3.qif" \
  "$P" convert "$W/inch2.csv" "$W/inch3.qif" --units mm

# dmo -> qif -> dmo with two tips: every point, normal and radius, each label and tip.
cat >"$W/tips.dmo" <<'EOF'
DMISMN/'two tips',05.3
UNITS/MM,ANGDEC
S(BIG)=SNSDEF/PROBE,INDEX,POL,0,90,0,0,1,150,2
S(SMALL) = SNSDEF/PROBE, INDEX, POL, 90, 0, 0, 0, 1, 120, 0.7
SNSLCT/S(BIG)
FA(A1)=FEAT/POINT,CART,10.125,-3.3,0.1,0,0,1
FA(A2)=FEAT/POINT,CART,11.5,-3.3,0.2,0,0,1
SNSLCT/S(SMALL)
FA(B1)=FEAT/POINT,CART,0.001,2.000000000001,3,0.6,0,0.8
SNSLCT/S(BIG)
FA(A3)=FEAT/POINT,CART,7,8,9,1,0,0
ENDFIL
EOF
"$P" convert "$W/tips.dmo" "$W/tips.qif" && validates "$W/tips.qif" || fail=1
check "grep -q '<ProbeRadii>1 1 0.35 1</ProbeRadii>' '$W/tips.qif'" "dmo -> qif: each point's radius"
"$P" convert "$W/tips.qif" "$W/tips2.dmo" || fail=1
check "[ \"\$(grep -E '^(FA|SNSLCT)' '$W/tips.dmo')\" = \"\$(grep -E '^(FA|SNSLCT)' '$W/tips2.dmo')\" ]" \
  "dmo -> qif -> dmo: the same points, labels and selections"
check "grep -qx 'S(SMALL)=SNSDEF/PROBE,INDEX,POL,0,0,0,0,1,0,0.7' '$W/tips2.dmo'" "dmo -> qif -> dmo: each tip's diameter"
"$P" convert "$W/tips.dmo" "$W/tips.csv" || fail=1
check "[ \"\$(cat '$W/tips.csv')\" = \"\$(printf 'x,y,z,i,j,k,r,label,tip\n10.125,-3.3,0.1,0,0,1,1,A1,BIG\n11.5,-3.3,0.2,0,0,1,1,A2,BIG\n0.001,2.000000000001,3,0.6,0,0.8,0.35,B1,SMALL\n7,8,9,1,0,0,1,A3,BIG')\" ]" \
  "dmo -> csv: x,y,z,i,j,k,r then label and tip"

# Compensation from QIF: the demo's points, each row's radius 1 mm in ProbeRadius (no --probe-radius), in two sets
# and a third of one point; the same figures as from the CSV; the output QIF validates.
demo_files "$W/demo" || { echo "FAIL: demo"; fail=1; }
awk -F, -v OFS=, 'NR == 1 { print $0, "r", "set"; next } { print $0, 1, (NR < 3000 ? 5 : 6) }' "$W/demo/raw.csv" >"$W/raw.csv"
"$P" convert "$W/raw.csv" "$W/raw.qif" && validates "$W/raw.qif" || fail=1
check "[ \$(grep -c '<ProbeRadius>1</ProbeRadius>' '$W/raw.qif') -eq 2 ]" "raw.qif: two sets, radius 1"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/raw.qif" --output "$W/out.qif" --json "$W/out.json" --quiet ||
  { echo "FAIL: compensate raw.qif to out.qif"; fail=1; }
validates "$W/out.qif"
check "grep -q '<MeasuredPointSet count=\"2998\" id=\"5\">' '$W/out.qif' && grep -q '<MeasuredPointSet count=\"4202\" id=\"6\">' '$W/out.qif'" \
  "out.qif: the input's sets, ids and counts"
check "[ \$(grep -c '<Compensated>true</Compensated>' '$W/out.qif') -eq 2 ]" "out.qif: compensated"
check "grep -q 'name=\"probecomp:status\" value=\"ok ok ' '$W/out.qif' && grep -q 'name=\"probecomp:u\"' '$W/out.qif'" "out.qif: statuses and u"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/raw.qif" --output "$W/out_qif.csv" --quiet || fail=1
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" --probe-radius 1 --output "$W/out_csv.csv" --quiet || fail=1
check "[ \"\$(cut -d, -f1-10 '$W/out_qif.csv')\" = \"\$(cat '$W/out_csv.csv')\" ]" "compensated from QIF: the CSV run's figures, row for row"
json_check "$W/out.json" "j['inputs']['tip_radii'] == [1]" "compensated from QIF: the radius from ProbeRadius"
# With characteristics: their definitions, nominals, items and measurements (status, value and its u, max, min) are
# in the document, which still validates; their figures are --json's, in the document's unit (mm here).
printf '{"datums": {"A": {"faces": [0]}}, "characteristics": [{"name": "P1", "faces": [0], "tolerance": 3.0},
  {"name": "P2", "faces": [0], "tolerance": 0.001, "datums": ["A"]}, {"name": "P3", "faces": [0], "tolerance": 0.2, "datums": ["B"]}]}' \
  | sed 's/"B"/"A"/; s/"P3", "faces": \[0\]/"P3", "faces": [0], "outside": 0.05/; s/]}]}$/]}], "alignment": ["A"]}/' >"$W/spec.json"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/raw.qif" --characteristics "$W/spec.json" --output "$W/judged.qif" \
  --json "$W/judged.json" --quiet 2>/dev/null || { echo "FAIL: compensate with characteristics to QIF"; fail=1; }
validates "$W/judged.qif" || fail=1
check "[ \$(grep -c '<SurfaceProfileCharacteristicMeasurement id=' '$W/judged.qif') -eq 3 ]" "judged.qif: three characteristic measurements"
check "grep -q '<CharacteristicStatusEnum>PASS</CharacteristicStatusEnum>' '$W/judged.qif' && grep -q '<CharacteristicStatusEnum>FAIL</CharacteristicStatusEnum>' '$W/judged.qif'" \
  "judged.qif: PASS and FAIL as --json's decisions"
# (The document's first measurement's Value, to the rounding of both texts: 9 decimals there, 9 digits in the JSON.)
json_check "$W/judged.json" "abs(float(__import__('re').search(r'<SurfaceProfileCharacteristicMeasurement .*?<Value[^>]*>([^<]+)</Value>', open('$W/judged.qif').read(), 16).group(1)) - j['characteristics'][0]['value']) <= 5.1e-10 + 5e-9 * abs(j['characteristics'][0]['value']) and '<OuterDisposition>0.050000000</OuterDisposition>' in open('$W/judged.qif').read()" \
  "judged.qif: the value and the outer disposition as --json's" || fail=1

# The datum reference frame A: one datum definition labelled A (its faces), one frame of it as primary, fitted by
# least squares, and the two characteristics in it refer to that frame; P1 (form only) to none. As measured: a
# coordinate system A tied to an actual transform, the frame's CAD-to-machine motion that --json gives as the output's
# transform (the specification aligns the output to A): its rotation's columns and origin.
check "python3 - '$W/judged.qif' '$W/judged.json' <<'PY'
import json, sys, xml.etree.ElementTree as ET
q = '{http://qifstandards.org/xsd/qif3}'
root = ET.parse(sys.argv[1]).getroot()
T = json.load(open(sys.argv[2]))['transform']
results = root.find(q + 'Results/' + q + 'MeasurementResultsSet/' + q + 'MeasurementResults')
actual = results.findall(q + 'ActualTransforms/' + q + 'Transform')
systems = root.findall(q + 'CoordinateSystems/' + q + 'CoordinateSystemDefinitions/' + q + 'CoordinateSystem')
tied = results.findall(q + 'CoordinateSystemActualTransformAssociations/' + q + 'CoordinateSystemActualTransformAssociation')
assert len(actual) == 1 and actual[0].findtext(q + 'Name') == 'A', 'one actual transform, of A'
assert len(systems) == 1 and systems[0].findtext(q + 'Name') == 'A', 'one coordinate system A'
assert len(tied) == 1 and tied[0].findtext(q + 'ActualTransformId') == actual[0].get('id') \\
    and tied[0].findtext(q + 'CoordinateSystemId') == systems[0].get('id'), 'A tied to its transform'
columns = [[float(v) for v in actual[0].findtext(q + 'Rotation/' + q + axis).split()]
           for axis in ('XDirection', 'YDirection', 'ZDirection')]
origin = [float(v) for v in actual[0].findtext(q + 'Origin').split()]
assert max(abs(columns[c][r] - T[r][c]) for r in range(3) for c in range(3)) < 1e-11, (columns, T)
assert max(abs(origin[r] - T[r][3]) for r in range(3)) < 1e-8, (origin, T)
datums = root.findall(q + 'DatumDefinitions/' + q + 'DatumDefinition')
frames = root.findall(q + 'DatumReferenceFrames/' + q + 'DatumReferenceFrame')
assert len(datums) == 1 and datums[0].findtext(q + 'DatumLabel') == 'A', 'one datum A'
assert datums[0].find(q + 'Attributes/' + q + 'AttributeStr').get('value') == '0', 'datum A on face 0'
assert len(frames) == 1 and frames[0].findtext(q + 'Name') == 'A', 'one frame A'
simple = frames[0].find(q + 'Datums/' + q + 'Datum/' + q + 'SimpleDatum')
assert simple.findtext(q + 'DatumDefinitionId') == datums[0].get('id')
assert simple.findtext(q + 'SubstituteFeatureAlgorithm/' + q + 'SubstituteFeatureAlgorithmEnum') == 'LEASTSQUARES'
assert frames[0].findtext(q + 'Datums/' + q + 'Datum/' + q + 'Precedence/' + q + 'PrecedenceEnum') == 'PRIMARY'
refs = {d.findtext(q + 'Name'): d.findtext(q + 'DatumReferenceFrameId')
        for d in root.iter(q + 'SurfaceProfileCharacteristicDefinition')}
assert refs == {'P1': None, 'P2': frames[0].get('id'), 'P3': frames[0].get('id')}, refs
PY" "judged.qif: datum A, its frame, and the characteristics that refer to it"

# Bad inputs: one line naming the file and the line, a non-zero exit, no output.
printf 'x,y,z\n1,2,3\n' >"$W/notxml.qif"
expect_error "notxml.qif:2: not XML" "$W/o1.csv" "$P" convert "$W/notxml.qif" "$W/o1.csv"
sed '1111s/count="219"/count="220"/' "$SAMPLE" >"$W/count.qif"
expect_error "count.qif:1113: MeasuredPointSet id=29: count is 220 but Points holds 219 points" "$W/o2.csv" \
  "$P" convert "$W/count.qif" "$W/o2.csv"
sed '1114s/false/true/' "$SAMPLE" >"$W/compensated.qif"
expect_error "compensated.qif:1114: MeasuredPointSet id=29: the points are compensated already" "$W/o3.csv" \
  "$P" compensate --cad "$W/demo/nominal.igs" --points "$W/compensated.qif" --output "$W/o3.csv"
sed '1113s/3.54516458565/3.545x/' "$SAMPLE" >"$W/token.qif"
expect_error "token.qif:1113: MeasuredPointSet id=29: Points: '3.545x' (number 1) is not a number" "$W/o4.qif" \
  "$P" convert "$W/token.qif" "$W/o4.qif"
sed 's/SNSLCT\/S(SMALL)/SNSLCT\/S(TINY)/' "$W/tips.dmo" >"$W/undefined.dmo"
expect_error "undefined.dmo:8: SNSLCT selects S(TINY), which no SNSDEF before it defines" "$W/o5.qif" \
  "$P" convert "$W/undefined.dmo" "$W/o5.qif"
for bad in 0 -1 abc; do
  sed "3s/150,2\$/150,$bad/" "$W/tips.dmo" >"$W/diameter.dmo"
  expect_error "diameter.dmo:3: sensor S(BIG): the ball diameter (the last number) must be a positive number, not '$bad'" \
    "$W/o6.csv" "$P" convert "$W/diameter.dmo" "$W/o6.csv"
done
expect_error "is the IN file" "" "$P" convert "$W/tips.dmo" "$W/tips.dmo"
check "grep -q 'S(BIG)' '$W/tips.dmo'" "the input is never overwritten"
expect_error "OUT must end in .csv, .dmo (DMIS) or .qif" "$W/o7.txt" "$P" convert "$W/tips.dmo" "$W/o7.txt"
check "[ $rc -eq 2 ]" "an unknown output format: exit 2 (usage)"

[ $fail -eq 0 ] && echo "qif: all checks passed"
exit $fail
