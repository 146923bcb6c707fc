#!/bin/sh
# study registration: the table prints, registration.json holds both routes' std/mean/ci95 for all six
# components, the proposed route's noise-free std is at most 1e-5 (deg and mm), and registration.csv has one
# row per trial and route; index.html shows Table 1 (the chart and the JSON's numbers). An unknown study name
# fails with a message. Usage: study_registration.sh PROBECOMP WORK_DIR
set -eu
P=$1; W=$2
rm -rf "$W"; mkdir -p "$W"
"$P" study registration --output-dir "$W/out" >"$W/table.txt"
grep -q 'Standard deviation of the registration error' "$W/table.txt" || { echo "FAIL: no table"; exit 1; }
J="$W/out/registration.json"
for key in '"proposed": {"std": {"rx"' '"conventional": {"std": {"rx"' '"mean": {"rx"' '"ci95": {"rx"' '"tz"'; do
  grep -q "$key" "$J" || { echo "FAIL: $key missing from $J"; exit 1; }
done
# The proposed std object is the first "std" in the file.
grep -o '"proposed": {"std": {[^}]*}' "$J" | head -1 | tr ',' '\n' | sed 's/.*: //; s/}//' |
  awk '{ v = $1 < 0 ? -$1 : $1; if (v > 1e-5) { print "FAIL: proposed std " $1; bad = 1 } } END { exit bad }'
rows=$(($(wc -l <"$W/out/registration.csv") - 1))
[ "$rows" -eq 60 ] || { echo "FAIL: $rows trial rows, expected 60"; exit 1; }
# Table 1 in index.html: one inline chart (registration.svg) and the JSON's numbers in the table.
[ "$(grep -o '<svg' "$W/out/index.html" | wc -l)" -eq 1 ] && [ -f "$W/out/registration.svg" ] ||
  { echo "FAIL: registration.svg not written or not inlined once in index.html"; exit 1; }
v=$(grep -o '"conventional": {"std": {"rx": [^,]*' "$J" | head -1 | sed 's/.*: //')
grep -q "<td>$v</td>" "$W/out/index.html" || { echo "FAIL: conventional std rx $v not in index.html"; exit 1; }
if "$P" study no-such-study >"$W/err.txt" 2>&1; then echo "FAIL: unknown study accepted"; exit 1; fi
grep -q 'no-such-study' "$W/err.txt" || { echo "FAIL: message does not name the study"; cat "$W/err.txt"; exit 1; }
echo "study registration: table, JSON, CSV and index.html written; proposed std <= 1e-5"
