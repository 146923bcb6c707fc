#!/bin/sh
# probecomp study analytic-cylinder, cylinder-misalignment and freeform: each prints its table and writes
# NAME.csv and NAME.json with the promised content, its figures (NAME*.svg) and NAME.section.html; index.html in the
# same directory gathers the sections of all of them, self-contained. Usage: studies.sh PROBECOMP WORK_DIR [light]
# light (the sanitizer build): the analytic cylinder alone; the index then holds its section. The other studies' code
# runs under the sanitizers in CylinderStudies.* and FreeformStudy.*, and every study goes through the same writers
# (CSV, JSON, SVG, sections, index); their 26 s there go to the Release run, with the free-form noise sweep.
set -u
P=$1; W=$2; LIGHT=${3:-}
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
"$P" study analytic-cylinder --output-dir "$W" >"$W/a.txt" || { echo "FAIL: analytic-cylinder"; exit 1; }
grep -q 'Fig. 5' "$W/a.txt" || { echo "FAIL: no Fig. 5 table"; fail=1; }
# The paper's example: about 0.03 mm.
json_value "$W/analytic-cylinder.json" "j['max_error_mm']" |
  awk '{ if ($1 < 0.029 || $1 > 0.032) { print "FAIL: max_error_mm " $1; exit 1 } }' || fail=1
[ "$(grep -c '^fig3,' "$W/analytic-cylinder.csv")" -eq 361 ] || { echo "FAIL: Fig. 3 series rows"; fail=1; }
[ "$(grep -c '^fig5,' "$W/analytic-cylinder.csv")" -eq 210 ] || { echo "FAIL: Fig. 5 series rows"; fail=1; }

if [ "$LIGHT" != light ]; then
  "$P" study cylinder-misalignment --output-dir "$W" >"$W/m.txt" || { echo "FAIL: cylinder-misalignment"; exit 1; }
  json_check "$W/cylinder-misalignment.json" "j['cad_better_everywhere'] and j['cad_std_below_sigma_from_10um']" \
    "the misalignment study's claims" || cat "$W/m.txt"
  [ "$(($(wc -l <"$W/cylinder-misalignment.csv") - 1))" -eq 12 ] || { echo "FAIL: 6 sigmas x 2 methods rows"; fail=1; }

  "$P" study freeform --output-dir "$W" >"$W/f.txt" || { echo "FAIL: freeform"; exit 1; }
  grep -q 'CAD-based (paper)' "$W/f.txt" || { echo "FAIL: no Table 2"; fail=1; }
  [ "$(($(wc -l <"$W/freeform.csv") - 1))" -eq 7200 ] || { echo "FAIL: freeform.csv rows"; fail=1; }
  json_check "$W/freeform.json" "j['cad']['points'] == 7200" "freeform.json: 7200 CAD-based points"
  json_check "$W/freeform.json" "j['cad_uncertainty']['mean_u_mm'] > 0" "freeform.json has no u figures"
  grep -q 'true error is within +-2u' "$W/f.txt" || { echo "FAIL: no coverage line"; fail=1; }
fi

if [ "$LIGHT" != light ]; then
  # The noise sweep, 0 included: one row per level; issue 19's bars on this case. No row flagged at either level;
  # without noise the largest error is at most 2 um; at 4.5 um std <= 1.3 um, max <= 9 um, +-2u covers 90-99 %;
  # at least 85 % in every region at both (without noise u is near its 0.1 um floor and covers everything).
  "$P" study freeform --noise 0,0.0045 --output-dir "$W" >"$W/fn.txt" || { echo "FAIL: freeform --noise sweep"; exit 1; }
  [ "$(($(wc -l <"$W/freeform-noise.csv") - 1))" -eq 2 ] || { echo "FAIL: freeform-noise.csv rows"; fail=1; }
  awk -F, 'NR == 2 { if ($6 > 0.002 || $7 != 0 || $10 < 0.85) { print "FAIL: sigma 0: " $0; exit 1 } }
           NR == 3 { if ($4 > 0.0013 || $6 > 0.009 || $7 != 0 || $9 < 0.90 || $9 > 0.99 || $10 < 0.85) { print "FAIL: sigma 4.5 um: " $0; exit 1 } }' \
    "$W/freeform-noise.csv" || { cat "$W/fn.txt"; fail=1; }
fi

# The figures: each study's SVG files and section, and index.html, one self-contained page of the sections run
# into $W, in the order of the paper (kStudyNames, the sweep after freeform), with every figure inline.
I="$W/index.html"
figures="analytic-cylinder-fig3.svg analytic-cylinder-fig5.svg"
sections="analytic-cylinder"
if [ "$LIGHT" != light ]; then
  figures="$figures cylinder-misalignment.svg freeform.svg freeform-noise.svg"
  sections="$sections cylinder-misalignment freeform freeform-noise"
fi
for f in $figures; do
  [ "$(grep -c '<svg' "$W/$f")" -eq 1 ] && grep -q '^<svg xmlns="http://www.w3.org/2000/svg" width="[0-9]*" height="[0-9]*"' "$W/$f" ||
    { echo "FAIL: $f is not one SVG"; fail=1; }
  grep -F -q "$(head -1 "$W/$f")" "$I" 2>/dev/null || { echo "FAIL: $f not inlined in index.html"; fail=1; }
done
for n in $sections; do
  [ -f "$W/$n.section.html" ] || { echo "FAIL: no $n.section.html"; fail=1; }
done
check_index() {  # $1: what was run last
  [ -f "$I" ] || { echo "FAIL: no index.html after $1"; return 1; }
  svgs=$(grep -o '<svg' "$I" | wc -l)
  expected=$(echo $figures | wc -w)
  [ "$svgs" -eq "$expected" ] || { echo "FAIL: $svgs inline SVGs in index.html after $1, expected $expected ($figures)"; return 1; }
  order=$(grep -o '<section id="[a-z-]*"' "$I" | sed 's/.*id="//; s/"//' | tr '\n' ' ')
  [ "$order" = "$sections " ] ||
    { echo "FAIL: sections after $1: $order"; return 1; }
  # Nothing fetched: no link, script, image, frame, CSS import or url(); no address but the SVG namespace.
  if grep -n -i -E 'src=|href|url\(|@import|<script|<link|<img|<iframe|<object|<embed' "$I"; then
    echo "FAIL: index.html references something outside itself"; return 1
  fi
  if grep -o -i -E '(https?|ftp|file)://[^" <]*' "$I" | grep -v -x 'http://www.w3.org/2000/svg'; then
    echo "FAIL: index.html names an address other than the SVG namespace"; return 1
  fi
  # The numbers in the tables are the JSON's and the printed tables': the paper's example's largest error, the
  # free-form CAD-based std and min, the misalignment study's conventional std at 40 um.
  v=$(json_value "$W/analytic-cylinder.json" "j['max_error_mm']")
  html_has_cell "$I" "$v" || { echo "FAIL: max_error_mm $v not in index.html"; return 1; }
  if [ "$LIGHT" != light ]; then
    for key in std min; do
      v=$(json_value "$W/freeform.json" "j['cad']['$key']")
      [ -n "$v" ] && html_has_cell "$I" "$v" || { echo "FAIL: freeform CAD $key '$v' not in index.html"; return 1; }
    done
    v=$(awk -F'|' '$1 ~ /^ +40 $/ { split($2, a, " "); print a[2] }' "$W/m.txt")
    [ -n "$v" ] && grep -q "<td>40</td><td>[-0-9.]*</td><td>$v</td>" "$I" ||
      { echo "FAIL: conventional std at 40 um '$v' not in index.html's Fig. 8 table"; return 1; }
  fi
  # Well-formed: each inline SVG parses as XML, and the page's elements nest.
  if command -v python3 >/dev/null 2>&1; then
    python3 - "$I" <<'PY' || return 1
import re, sys, xml.etree.ElementTree as ET
from html.parser import HTMLParser
page = open(sys.argv[1], encoding="utf-8").read()
for svg in re.findall(r"<svg.*?</svg>", page, re.S):
    root = ET.fromstring(svg)
    assert root.tag == "{http://www.w3.org/2000/svg}svg", root.tag
    assert root.find("{http://www.w3.org/2000/svg}title") is not None, "an SVG without a title"
class Nesting(HTMLParser):
    void = {"meta", "br", "img", "hr", "input", "link"}
    def __init__(self):
        super().__init__(); self.stack = []
    def handle_starttag(self, tag, attrs):
        if tag not in self.void: self.stack.append(tag)
    def handle_startendtag(self, tag, attrs):
        pass
    def handle_endtag(self, tag):
        if not self.stack or self.stack.pop() != tag: raise SystemExit(f"FAIL: </{tag}> closes nothing open")
n = Nesting(); n.feed(page); n.close()
if n.stack: raise SystemExit(f"FAIL: unclosed {n.stack}")
PY
  fi
}
check_index "the last study" || fail=1
# Running a study again replaces its section (and figures) rather than adding one.
"$P" study analytic-cylinder --output-dir "$W" >"$W/a2.txt" || { echo "FAIL: analytic-cylinder again"; exit 1; }
check_index "analytic-cylinder again" || fail=1

[ $fail -eq 0 ] && echo "studies: analytic-cylinder, cylinder-misalignment and freeform tables (and the noise sweep), CSV, JSON, SVG figures and index.html as promised"
exit $fail
