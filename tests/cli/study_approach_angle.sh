#!/bin/sh
# study approach-angle (issue 52, the paper's Fig. 3 with a lobing probe): the table prints by bins of the approach
# angle, approach-angle.json holds the qualification, the bars and ISO 10360-5's probing test, approach-angle.csv
# one row per touch, and index.html the chart and the JSON's numbers. The numbers themselves are held by the unit
# test ApproachAngleStudy.* against closed forms; here: the command, its files and that they agree.
# Usage: study_approach_angle.sh PROBECOMP WORK_DIR
set -eu
P=$1; W=$2
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
"$P" study approach-angle --output-dir "$W/out" >"$W/table.txt"
grep -q 'the radius by direction: degree' "$W/table.txt" || { echo "FAIL: no qualification line"; cat "$W/table.txt"; exit 1; }
[ "$(grep -c '^ *[0-9]*-[0-9]* ' "$W/table.txt")" -eq 18 ] || { echo "FAIL: not 18 bins in the table"; cat "$W/table.txt"; exit 1; }
J="$W/out/approach-angle.json"
json_check "$J" "j['touches'] == 500 and len(j['bins']) == 18 and j['units'] == 'mm'" "500 touches in 18 bins"
json_check "$J" "j['qualified']['meets_bars'] and j['qualified']['worst_bin_mean_mm'] <= 0.0007 and j['qualified']['worst_bin_std_mm'] <= 0.0012" \
  "qualified: the issue's bars met"
json_check "$J" "j['cad']['bin_mean_spread_mm'] > 3 * j['qualified']['bin_mean_spread_mm']" \
  "the nominal radius leaves the pre-travel's spread in the bins"
json_check "$J" "j['iso10360_5']['touches'] == 25 and j['iso10360_5']['form_model_mm'] < j['iso10360_5']['form_plain_mm']" \
  "ISO 10360-5: the form error falls with the radius by direction"
json_check "$J" "sum(b['qualified']['points'] for b in j['bins']) + j['qualified']['untrusted'] == 500" \
  "every touch in a bin or counted untrusted"
[ $fail -eq 0 ] || exit 1
rows=$(($(wc -l <"$W/out/approach-angle.csv") - 1))
[ "$rows" -eq 500 ] || { echo "FAIL: $rows touch rows, expected 500"; exit 1; }
# The printed worst bin mean is the JSON's.
v=$(json_value "$J" "'%.2f' % (1000 * j['qualified']['worst_bin_mean_mm'])" | tr -d '"')
grep -q "worst bin mean $v um" "$W/table.txt" || { echo "FAIL: worst bin mean $v not printed"; exit 1; }
[ "$(grep -o '<svg' "$W/out/index.html" | wc -l)" -eq 1 ] && [ -f "$W/out/approach-angle.svg" ] ||
  { echo "FAIL: approach-angle.svg not written or not inlined once in index.html"; exit 1; }
v=$(json_value "$J" "'%.2f' % (1000 * j['bins'][4]['qualified']['mean'])" | tr -d '"')
html_has_cell "$W/out/index.html" "$v" || { echo "FAIL: bin 5's qualified mean $v not in index.html"; exit 1; }
echo "study approach-angle: table, JSON, CSV and index.html written; the qualified bins within the issue's bars"
