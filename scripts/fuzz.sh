#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/) in the sanitizer build, build-sanitize/ (clang, AddressSanitizer and
# UndefinedBehaviorSanitizer: scripts/sanitize_build.sh), and runs each for SECONDS (default 30), as many at once as
# there are cores, from its seed corpus: fuzz/corpus/TARGET, plus the CAD files for the CAD targets and the QIF sample
# for the QIF one. Exits non-zero if any target crashes, leaks or trips a sanitizer; libFuzzer leaves the input as
# build-sanitize/fuzz-findings/crash-* (keep it as a regression test). Prints the executions of each target.
#   scripts/fuzz.sh [SECONDS] [TARGET...]      (targets: points_csv points_dmis points_qif transform cad_step cad_iges)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
./scripts/setup.sh --fuzz
source scripts/sanitize_build.sh
configure_sanitize_build
out=$sanitize_build_dir/fuzz-findings
targets=(points_csv points_dmis points_qif transform cad_step cad_iges)
[ $# -gt 1 ] && targets=("${@:2}")
cmake --build "$sanitize_build_dir" -j"$(nproc)" --target "${targets[@]/#/fuzz_}"

mkdir -p "$out"
# One target: its line of summary on standard output, status 1 if it failed.
fuzz_one() {
  local target=$1
  # The working corpus grows in fuzz-corpus/ of the build; the seeds in the source tree are only read.
  work="$sanitize_build_dir/fuzz-corpus/$target"
  mkdir -p "$work"
  seeds=()
  [ -d "fuzz/corpus/$target" ] && seeds+=("fuzz/corpus/$target")
  # Test files as further seeds, copied into a folder of their own (libFuzzer takes folders as corpora).
  case $target in
    points_qif) files=(tests/data/cad/*.QIF) ;;
    cad_step) files=(tests/data/cad/asitus_wavy-cube.stp) ;;
    cad_iges) files=(tests/data/cad/iges_spec_surf128.igs) ;;
    *) files=() ;;
  esac
  if [ ${#files[@]} -gt 0 ]; then
    mkdir -p "$sanitize_build_dir/fuzz-seeds/$target" && cp "${files[@]}" "$sanitize_build_dir/fuzz-seeds/$target/" &&
      seeds+=("$sanitize_build_dir/fuzz-seeds/$target")
  fi
  log="$out/$target.log"
  # -max_len: the CAD seeds are tens of kB; the rest stay small so that mutations stay near the grammar.
  max_len=4096
  case $target in cad_*|points_qif) max_len=65536 ;; esac
  status=0
  "$sanitize_build_dir/fuzz/fuzz_$target" "$work" "${seeds[@]}" -max_total_time="$seconds" -max_len="$max_len" \
    -artifact_prefix="$out/$target-" -print_final_stats=1 >"$log" 2>&1 || status=$?
  if [ $status -eq 0 ]; then
    runs=$(grep -m1 -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo '?')
    echo "fuzz_$target: ok, $runs executions in ${seconds} s"
  else
    # A status above 128 with no report in the log is a death by that signal minus 128 that nothing could catch.
    echo "fuzz_$target: FAILED with status $status (see $log)"
    tail -20 "$log"
    return 1
  fi
}
# The targets side by side, one per core (each libFuzzer process is single-threaded), their summaries in order.
for target in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  fuzz_one "$target" >"$out/$target.summary" &
done
wait
failed=0
for target in "${targets[@]}"; do
  cat "$out/$target.summary"
  if grep -q FAILED "$out/$target.summary"; then failed=1; fi
done
exit $failed
