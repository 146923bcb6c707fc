#!/bin/sh
# Faults a shop floor meets (issue 25), from the command line:
#  - a read-only output directory and a full disk: one line naming the file and the system's reason, exit 3,
#    nothing left behind (a private mount namespace gives both, even to root, which chmod cannot stop);
#  - SIGINT or SIGTERM at any moment of a run: every output whole, or none and no temporary;
#  - the same output bytes on one core as on two (oneTBB sizes its pool from the CPU affinity mask).
# Usage: faults.sh PROBECOMP WORK_DIR [light]
# light (the sanitizer build, about ten times slower): a scan of 8 k points instead of 32 k, still seconds a run there.
set -u
P=$1; W=$2; LIGHT=${3:-}
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
demo_files "$W/demo" || { echo "FAIL: demo"; exit 1; }
N="$W/demo/nominal.igs"
# A larger scan (32 k points), so that an interrupt can land in every stage of a run.
"$P" simulate --cad "$N" --spacing "$([ "$LIGHT" = light ] && echo 0.8 || echo 0.4)" --probe-radius 1 --noise 0.001 --misalign 0.1,0,0,0,0,0.2 \
  --output-dir "$W/scan" >/dev/null || { echo "FAIL: simulate"; exit 1; }
R="$W/scan/raw.csv"

# --- Read-only directory and full disk -----------------------------------------------------------------------
mkdir -p "$W/ro" "$W/tiny"
if unshare -m true 2>/dev/null; then
  unshare -m sh -c "mount --bind '$W/ro' '$W/ro' && mount -o remount,bind,ro '$W/ro' &&
    '$P' compensate --cad '$N' --points '$R' --probe-radius 1 --output '$W/ro/out.csv' --json '$W/ro/out.json' --quiet" \
    >"$W/stdout" 2>"$W/stderr"
  rc=$?
  check "[ $rc -eq 3 ]" "read-only directory: exit 3 (was $rc)"
  check "[ \$(wc -l <'$W/stderr') -eq 1 ] && grep -q 'ro/out.csv: cannot be written (Read-only file system)' '$W/stderr'" \
    "read-only directory: one line naming the file and the reason ($(cat "$W/stderr"))"
  # 100 kB of room: the 32 k-row output (about 4 MB; 8 k rows light) does not fit.
  unshare -m sh -c "mount -t tmpfs -o size=100k none '$W/tiny' &&
    '$P' compensate --cad '$N' --points '$R' --probe-radius 1 --output '$W/tiny/out.csv' --json '$W/tiny/out.json' --quiet;
    rc=\$?; ls -A '$W/tiny' >'$W/tiny.left'; exit \$rc" >"$W/stdout" 2>"$W/stderr"
  rc=$?
  check "[ $rc -eq 3 ]" "full disk: exit 3 (was $rc)"
  check "[ \$(wc -l <'$W/stderr') -eq 1 ] && grep -q 'tiny/out.csv: cannot be written (No space left on device)' '$W/stderr'" \
    "full disk: one line naming the file and the reason ($(cat "$W/stderr"))"
  check "[ ! -s '$W/tiny.left' ]" "full disk: nothing left on it ($(cat "$W/tiny.left"))"
elif [ "$(id -u)" -ne 0 ]; then
  chmod 555 "$W/ro"
  expect_error "ro/out.csv: cannot be written (Permission denied)" "$W/ro/out.csv" \
    "$P" compensate --cad "$N" --points "$R" --probe-radius 1 --output "$W/ro/out.csv" --quiet
  chmod 755 "$W/ro"
  echo "note: no mount namespace here; full disk not tried"
else
  echo "FAIL: running as root without mount namespaces: neither a read-only directory nor a full disk can be made"
  fail=1
fi

# --- Interrupted runs ----------------------------------------------------------------------------------------
# One uninterrupted run for the reference bytes and the run's length.
"$P" compensate --cad "$N" --points "$R" --probe-radius 1 --output "$W/ref.csv" --json "$W/ref.json" \
  --report "$W/ref.html" --quiet || { echo "FAIL: reference run"; fail=1; }
interrupted=0; finished=0
for sig in INT TERM; do
  for delay in 0.02 0.05 0.1 0.15 0.2 0.3 0.4 0.5 0.6 0.8; do
    d="$W/int_${sig}_$delay"; mkdir -p "$d"
    # env --default-signal: a background job of a script starts with SIGINT ignored; a user's shell does not.
    env --default-signal=INT "$P" compensate --cad "$N" --points "$R" --probe-radius 1 --output "$d/out.csv" \
      --json "$d/out.json" --report "$d/out.html" --quiet 2>"$d/stderr" &
    pid=$!
    sleep "$delay"
    kill -s "$sig" "$pid" 2>/dev/null
    wait "$pid"; rc=$?
    left=$(ls -A "$d" | grep -v '^stderr$' | tr '\n' ' ')
    if [ -z "$left" ]; then
      interrupted=$((interrupted + 1))
      case $sig in INT) want=130 ;; TERM) want=143 ;; esac
      check "[ $rc -eq $want ]" "SIG$sig after ${delay}s: exit $want, by the signal (was $rc)"
    else
      finished=$((finished + 1))
      check "[ '$left' = 'out.csv out.html out.json ' ] && cmp -s '$d/out.csv' '$W/ref.csv'" \
        "SIG$sig after ${delay}s: every output whole or none (exit $rc; left: $left)"
    fi
  done
done
echo "interrupted runs: $interrupted stopped with nothing written, $finished finished whole"
check "[ $interrupted -gt 0 ]" "some interrupt landed inside a run"

# --- One core and two ----------------------------------------------------------------------------------------
check "[ \$(taskset -c 0 nproc) -eq 1 ]" "taskset gives one core"
taskset -c 0 "$P" compensate --cad "$N" --points "$R" --probe-radius 1 --output "$W/one.csv" --json "$W/one.json" --quiet
check "cmp -s '$W/one.csv' '$W/ref.csv'" "the same output bytes on one core as on all ($(nproc))"
without_timings="{k: v for k, v in j.items() if k != 'timings'}"
check "[ \"\$(json_value '$W/one.json' \"$without_timings\")\" = \"\$(json_value '$W/ref.json' \"$without_timings\")\" ]" \
  "the same JSON (but its timings) on one core as on all"
exit $fail
