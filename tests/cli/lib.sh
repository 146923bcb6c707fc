# Sourced by the CLI test scripts; needs W (work directory) and fail (0 or 1) set by the caller.
# expect_error TEXT_IN_MESSAGE OUTPUT_FILE command...: the command fails with one line on standard error that
# contains TEXT, and leaves no OUTPUT_FILE (nor its temporary, OUTPUT.partial.EXT) behind.
expect_error() {
  text=$1; out=$2; shift 2
  "$@" >"$W/stdout" 2>"$W/stderr"; rc=$?
  lines=$(wc -l <"$W/stderr")
  if [ $rc -eq 0 ]; then echo "FAIL (exit 0): $*"; fail=1; fi
  if [ "$lines" -ne 1 ]; then echo "FAIL ($lines lines on stderr): $*"; cat "$W/stderr"; fail=1; fi
  if ! grep -q -- "$text" "$W/stderr"; then echo "FAIL (no '$text' in message): $*"; cat "$W/stderr"; fail=1; fi
  if [ -n "$out" ] && { ls "$out"* >/dev/null 2>&1 || ls "${out%.*}.partial"* >/dev/null 2>&1; }; then
    echo "FAIL (output left behind): $*"; fail=1
  fi
}

# check CONDITION DESCRIPTION: evaluates CONDITION; when false, prints "FAIL: DESCRIPTION" and sets fail=1.
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; fi; }
# status_of command...: the command's exit status, its output discarded.
status_of() { "$@" >/dev/null 2>&1; echo $?; }
