#!/bin/sh
# Issue 22: the HTML report, checked by tests/results/check_report.py (self-contained; its numbers the JSON's; rendered by
# headless Chromium offline with no console message, the 3-D view drawn and not blank) on
#  - the demo's own report.html, and compensate --report --json --tolerance on the demo's files;
#  - (not light) a real CAD sample with simulated points: the die-casting part (asitus_repatch-hpdc.stp), faces 0-20,
#    no tolerance (the colour bar from the deviations themselves);
#  - (not light) about 100 000 points on the demo's panel: the report stays under 8 MB and still renders.
# The checker must fail on a report that loads something from outside, logs to the console, draws nothing, or
# disagrees with its JSON. A bad --tolerance is a usage error (exit 2) that writes nothing.
# Usage: report.sh PROBECOMP CAD_DIR WORK_DIR [light]   (light, the sanitizer build: no die-casting part (the writer runs
# under the sanitizers on the demo here and in HtmlReport.*, that part's outline in RegisteredOutline.*), no
# 100 000-point run, and the checker's own tests left to the Release run)
set -u
P=$1; CAD=$2; W=$3; LIGHT=${4:-}
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
CHECK="python3 $(dirname "$0")/../results/check_report.py"
command -v chromium >/dev/null || { echo "FAIL: chromium is not installed (scripts/setup.sh --tests installs it)"; exit 1; }

demo_files "$W/demo" || { echo "FAIL: demo"; fail=1; }
echo "the demo's report:"
$CHECK "$W/demo/report.html" - --chromium --expect-tolerance --expect-difference || fail=1
# With two characteristics (the panel's form, and its profile to itself as datum A), which the view colours by too.
printf '{"datums": {"A": {"faces": [0]}}, "characteristics": [{"name": "form", "faces": [0], "tolerance": 0.05},
  {"name": "to A", "faces": [0], "tolerance": 0.02, "outside": 0.005, "datums": ["A"]}]}' >"$W/spec.json"
"$P" compensate --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" --probe-radius 1 --tolerance -0.05,0.05 \
  --characteristics "$W/spec.json" --report "$W/demo.html" --json "$W/demo.json" --output "$W/demo_out.csv" --quiet \
  || { echo "FAIL: compensate the demo with --report"; fail=1; }
echo "compensate --report on the demo's files:"
$CHECK "$W/demo.html" "$W/demo.json" --chromium --expect-tolerance --expect-difference || fail=1
# The tolerance's counts in the JSON are the deviations outside the band, counted here from the output CSV.
out=$(awk -F, 'NR > 1 && $10 == "ok" && ($7 < -0.05 || $7 > 0.05) { n++ } END { print n + 0 }' "$W/demo_out.csv")
json_check "$W/demo.json" "j['deviation']['tolerance'] == [-0.05, 0.05] and j['deviation']['out_of_tolerance'] == $out" \
  "the JSON counts the $out ok rows of the CSV outside -0.05..0.05 mm"

# The CAD-based minus conventional summary, recomputed here from the files: the output's contact point and normal
# against the raw centre moved 1 mm against its approach normal, over the ok rows.
awk -F, 'NR == FNR { if (FNR > 1) { n = sqrt($4 * $4 + $5 * $5 + $6 * $6); cx[FNR] = $1 - $4 / n; cy[FNR] = $2 - $5 / n; cz[FNR] = $3 - $6 / n }; next }
  FNR > 1 && $10 == "ok" { d = 1000 * (($1 - cx[FNR]) * $4 + ($2 - cy[FNR]) * $5 + ($3 - cz[FNR]) * $6); k++; s += d; q += d * d
    if (d < 0) d = -d; if (d > m) m = d }
  END { mean = s / k; printf "%d %.2f %.2f %.2f\n", k, mean, sqrt(q / k - mean * mean), m }' \
  "$W/demo/raw.csv" "$W/demo_out.csv" >"$W/difference.txt"
sed -n 's|.*<table id="difference-summary">.*<tr><td>\([^<]*\)</td><td>\([^<]*\)</td><td>\([^<]*\)</td><td>\([^<]*\)</td></tr></table>.*|\1 \2 \3 \4|p' \
  "$W/demo.html" >"$W/difference_report.txt"
echo "CAD-based minus conventional (points, mean, std, largest, um): from the files $(cat "$W/difference.txt"); the report $(cat "$W/difference_report.txt")"
check "awk 'NR == FNR { for (i = 1; i <= 4; ++i) a[i] = \$i; next } { bad = (\$1 != a[1]); for (i = 2; i <= 4; ++i) if ((\$i - a[i]) > 0.011 || (a[i] - \$i) > 0.011) bad = 1 }
  END { exit bad || NR != 2 }' '$W/difference.txt' '$W/difference_report.txt'" \
  "the report's CAD-based minus conventional summary is the one recomputed from the output and the raw points"

if [ "$LIGHT" != light ]; then
  HPDC="$CAD/asitus_repatch-hpdc.stp"
  "$P" simulate --cad "$HPDC" --spacing 2 --faces 0-20 --probe-radius 1 --misalign 0.1,0.05,-0.05,0.3,0.2,0 \
    --noise 0.002 --seed 3 --output-dir "$W/hpdc" >/dev/null || { echo "FAIL: simulate on the die-casting part"; fail=1; }
  "$P" compensate --cad "$HPDC" --points "$W/hpdc/raw.csv" --probe-radius 1 --report "$W/hpdc.html" --json "$W/hpdc.json" \
    --output "$W/hpdc_out.csv" --quiet 2>/dev/null || { echo "FAIL: compensate the die-casting part"; fail=1; }
  echo "the die-casting part:"
  $CHECK "$W/hpdc.html" "$W/hpdc.json" --chromium --expect-difference || fail=1
  check "[ \$(grep -c '<tr><td>' '$W/hpdc.html') -gt 20 ]" "the die-casting part's report has a row per face"
fi

# The checker fails where it should (not in the light run: this tests the checker and Chromium, not probecomp).
sabotaged() {  # NAME SED_EXPRESSION [JSON]: the checker must reject the demo's report so changed
  sed "$2" "$W/demo.html" >"$W/bad_$1.html"
  if $CHECK "$W/bad_$1.html" "${3:-$W/demo.json}" --chromium --expect-tolerance --expect-difference >"$W/bad_$1.txt" 2>&1; then
    echo "FAIL: the checker passed a report that $1"; fail=1
  else
    echo "rejected, as it should be, a report that $1: $(grep FAIL "$W/bad_$1.txt")"
  fi
}
if [ "$LIGHT" != light ]; then
  sabotaged "loads an image" 's|<body>|<body><img alt="" src="https://example.com/x.png">|'
  sabotaged "loads a style sheet" 's|</head>|<link rel="stylesheet" href="style.css"></head>|'
  sabotaged "throws an error" 's|</body>|<script>no_such_function();</script></body>|'
  sabotaged "draws nothing" 's|  function draw() {|  function draw() { return;|'
  sabotaged "does not zoom" 's|view.zoom \*= Math.exp(-e.deltaY \* 0.001);|view.zoom *= 1;|'
  sed 's|"ok": \([0-9]*\),|"ok": 1\1,|' "$W/demo.json" >"$W/bad.json"
  sabotaged "disagrees with its JSON" 's|x|x|' "$W/bad.json"
fi

# A bad tolerance band: a usage error naming --tolerance, nothing written.
for t in 0.05,-0.05 0.01,0.01 abc 0.05 ,0.05 nan,1 0.01,inf; do
  expect_error "--tolerance" "$W/bad.html" "$P" compensate --cad "$W/demo/nominal.igs" --points "$W/demo/raw.csv" \
    --probe-radius 1 --tolerance "$t" --report "$W/bad.html" --json "$W/bad.json2"
  check "[ \$(status_of '$P' compensate --cad '$W/demo/nominal.igs' --points '$W/demo/raw.csv' --probe-radius 1 --tolerance '$t') -eq 2 ]" \
    "--tolerance $t: exit status 2"
  check "[ ! -e '$W/bad.json2' ]" "--tolerance $t: no JSON written"
done

if [ "$LIGHT" != light ]; then
  "$P" simulate --cad "$W/demo/nominal.igs" --spacing 0.23 --probe-radius 1 --misalign 0,0,0.2,0,1.5,0 \
    --deform bump:20,5,0,0.3,12 --noise 0.0045 --seed 1 --output-dir "$W/big" >/dev/null || { echo "FAIL: simulate 100 000"; fail=1; }
  "$P" compensate --cad "$W/demo/nominal.igs" --points "$W/big/raw.csv" --probe-radius 1 --report "$W/big.html" \
    --json "$W/big.json" --output "$W/big_out.csv" --quiet || { echo "FAIL: compensate 100 000"; fail=1; }
  rows=$(($(wc -l <"$W/big/raw.csv") - 1)); bytes=$(wc -c <"$W/big.html")
  echo "$rows points: report of $bytes bytes"
  check "[ $rows -gt 95000 ] && [ $bytes -le 8000000 ]" "a report of about 100 000 points is at most 8 MB"
  $CHECK "$W/big.html" "$W/big.json" --chromium --expect-difference || fail=1
fi
exit $fail
