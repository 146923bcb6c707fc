# Sourced by the CLI test scripts; needs W (work directory) and fail (0 or 1) set by the caller.
# expect_error TEXT_IN_MESSAGE OUTPUT_FILE command...: the command fails with one line on standard error that
# contains TEXT, and leaves no OUTPUT_FILE (nor its temporary, OUTPUT.partial.EXT) behind. Progress lines
# ("probecomp: [###---] ...") do not count: a run that takes more than a second before it fails (a slow machine, the
# sanitizer build) prints them in a log, as it should.
expect_error() {
  text=$1; out=$2; shift 2
  "$@" >"$W/stdout" 2>"$W/stderr"; rc=$?
  lines=$(grep -cvE '^probecomp: \[[#-]+\] ' "$W/stderr" || true)
  if [ $rc -eq 0 ]; then echo "FAIL (exit 0): $*"; fail=1; fi
  if [ "$lines" -ne 1 ]; then echo "FAIL ($lines lines on stderr): $*"; cat "$W/stderr"; fail=1; fi
  if ! grep -q -- "$text" "$W/stderr"; then echo "FAIL (no '$text' in message): $*"; cat "$W/stderr"; fail=1; fi
  if [ -n "$out" ] && { ls "$out"* >/dev/null 2>&1 || ls "${out%.*}.partial"* >/dev/null 2>&1; }; then
    echo "FAIL (output left behind): $*"; fail=1
  fi
}

# demo_files DIR: the demo's files (nominal.igs, raw.csv, ...) in DIR: copied from PROBECOMP_DEMO_FILES, where ctest's
# fixture cli.demo_files made them once, or made by `probecomp demo` when the script runs on its own. Needs P.
demo_files() {
  if [ -n "${PROBECOMP_DEMO_FILES:-}" ] && [ -s "$PROBECOMP_DEMO_FILES/raw.csv" ]; then
    mkdir -p "$1" && cp "$PROBECOMP_DEMO_FILES"/* "$1"/
  else
    "$P" demo --output-dir "$1" >/dev/null
  fi
}

# check CONDITION DESCRIPTION: evaluates CONDITION; when false, prints "FAIL: DESCRIPTION" and sets fail=1.
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; fi; }
# status_of command...: the command's exit status, its output discarded.
status_of() { "$@" >/dev/null 2>&1; echo $?; }
# json_check FILE CONDITION DESCRIPTION: CONDITION, a Python expression over the file's parsed JSON `j` (e.g.
# "j['registration']['starts'] == 1"), holds; else prints "FAIL: DESCRIPTION", sets fail=1 and returns 1. A file that is not
# JSON fails too.
json_check() {
  if ! python3 -c 'import json, sys; j = json.load(open(sys.argv[1])); sys.exit(0 if eval(sys.argv[2]) else 1)' "$1" "$2"; then
    echo "FAIL: $3"; fail=1; return 1
  fi
}
# json_value FILE EXPRESSION: the Python EXPRESSION over the parsed JSON `j`, printed as JSON (0.25, true, "ok").
json_value() { python3 -c 'import json, sys; j = json.load(open(sys.argv[1])); print(json.dumps(eval(sys.argv[2])))' "$1" "$2"; }
# html_has_cell FILE NUMBER: FILE has a table cell <td>X</td> whose number X is NUMBER (compared as numbers: the
# table and the JSON may write one value with different digits, 1.5e-06 and 1.500000e-06).
html_has_cell() {
  python3 -c 'import re, sys
v = float(sys.argv[2])
sys.exit(0 if any(float(c) == v for c in re.findall(r"<td>([-+0-9.eE]+)</td>", open(sys.argv[1]).read())) else 1)' "$1" "$2"
}
