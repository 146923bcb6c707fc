#!/bin/sh
# study registration: the table prints, registration.json holds both routes' std/mean/ci95 for all six
# components, the proposed route's noise-free std is at most 1e-5 (deg and mm), and registration.csv has one
# row per trial and route; index.html shows Table 1 (the chart and the JSON's numbers). An unknown study name
# fails with a message. Usage: study_registration.sh PROBECOMP WORK_DIR
set -eu
P=$1; W=$2
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
"$P" study registration --output-dir "$W/out" >"$W/table.txt"
grep -q 'Standard deviation of the registration error' "$W/table.txt" || { echo "FAIL: no table"; exit 1; }
J="$W/out/registration.json"
pose="['rx', 'ry', 'rz', 'tx', 'ty', 'tz']"
json_check "$J" "all(list(j[route][s]) == $pose for route in ['proposed', 'conventional'] for s in ['std', 'mean', 'ci95'])" \
  "both routes' std, mean and ci95 for all six components in $J"
json_check "$J" "all(abs(v) <= 1e-5 for v in j['proposed']['std'].values())" "the proposed route's std within 1e-5"
[ $fail -eq 0 ] || exit 1
rows=$(($(wc -l <"$W/out/registration.csv") - 1))
[ "$rows" -eq 60 ] || { echo "FAIL: $rows trial rows, expected 60"; exit 1; }
# Table 1 in index.html: one inline chart (registration.svg) and the JSON's numbers in the table.
[ "$(grep -o '<svg' "$W/out/index.html" | wc -l)" -eq 1 ] && [ -f "$W/out/registration.svg" ] ||
  { echo "FAIL: registration.svg not written or not inlined once in index.html"; exit 1; }
v=$(json_value "$J" "j['conventional']['std']['rx']")
html_has_cell "$W/out/index.html" "$v" || { echo "FAIL: conventional std rx $v not in index.html"; exit 1; }
if "$P" study no-such-study >"$W/err.txt" 2>&1; then echo "FAIL: unknown study accepted"; exit 1; fi
grep -q 'no-such-study' "$W/err.txt" || { echo "FAIL: message does not name the study"; cat "$W/err.txt"; exit 1; }
echo "study registration: table, JSON, CSV and index.html written; proposed std <= 1e-5"
