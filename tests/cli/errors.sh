#!/bin/sh
# Bad input: one line on standard error naming the file or cause, a non-zero exit, no output file left behind.
# Usage: errors.sh PROBECOMP CAD_DIR WORK_DIR
set -u
P=$1; CAD=$2; W=$3
rm -rf "$W"; mkdir -p "$W"
fail=0
. "$(dirname "$0")/lib.sh"
printf 'x,y,z\n1,2,3\n' >"$W/good.csv"
printf 'x,y,z\n1,2,3\n4,five,6\n' >"$W/bad_number.csv"
printf 'x,y\n1,2\n' >"$W/no_z.csv"
printf 'x,y,z\n1,2,nan\n' >"$W/nan.csv"
printf 'x,y,z\n' >"$W/empty.csv"
head -c 5000 "$CAD/asitus_wavy-cube.stp" >"$W/truncated.stp"
expect_error "no such file" "" "$P" info "$W/missing.stp"
expect_error "truncated.stp" "" "$P" info "$W/truncated.stp"
expect_error "unknown CAD format" "" "$P" info "$W/good.csv"
expect_error "bad_number.csv:3" "$W/out.csv" "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/bad_number.csv" --output "$W/out.csv"
expect_error "x, y and z" "$W/out.csv" "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/no_z.csv" --output "$W/out.csv"
expect_error "nan.csv:2" "$W/out.csv" "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/nan.csv" --output "$W/out.csv"
expect_error "no points" "$W/out.csv" "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/empty.csv" --output "$W/out.csv"
expect_error "truncated" "$W/out.csv" "$P" project --cad "$W/truncated.stp" --points "$W/good.csv" --output "$W/out.csv"
expect_error "does not exist" "$W/plan.csv" "$P" plan "$CAD/asitus_wavy-cube.stp" --spacing 0.1 --faces 99 --output "$W/plan.csv"
expect_error "spacing" "$W/plan.csv" "$P" plan "$CAD/asitus_wavy-cube.stp" --spacing -1 --output "$W/plan.csv"
# compensate reads the points and the model side by side; the points' errors (a bad row, a missing tip radius) still
# come before the model's, as when they were read one after the other.
printf 'x,y,z,r\n1,2,3,1\n4,5,6,\n' >"$W/no_radius.csv"
expect_error "no_radius.csv:3" "$W/out.csv" "$P" compensate --cad "$W/missing.stp" --points "$W/no_radius.csv" --output "$W/out.csv"
expect_error "bad_number.csv:3" "$W/out.csv" "$P" compensate --cad "$W/missing.stp" --points "$W/bad_number.csv" --probe-radius 1 --output "$W/out.csv"
# A unit the file states against the one --units declares: the library says the cause, the command adds the option.
printf '# lengths in inch\nx,y,z\n1,2,3\n' >"$W/inch.csv"
expect_error "inch.csv:1: the file says its lengths are in inch, not in mm as --units says$" "$W/out.csv" \
  "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/inch.csv" --units mm --output "$W/out.csv"
# project reads every point format (io/point_files.hpp): a DMIS file's bad point names its line.
printf 'FA(P1)=FEAT/POINT,CART,1,2\n' >"$W/short.dmo"
expect_error "short.dmo:1" "$W/out.csv" "$P" project --cad "$CAD/asitus_wavy-cube.stp" --points "$W/short.dmo" --output "$W/out.csv"
exit $fail
