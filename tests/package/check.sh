#!/bin/sh
# The package as a consumer sees it: install the build to a fresh prefix, build the README's C++ example against
# that prefix alone with find_package(probecomp), and run it on the demo's files.
# Usage: check.sh BUILD_DIR README WORK_DIR [EXTRA_CXX_FLAGS]
set -u
B=$1; README=$2; W=$3; FLAGS=${4:-}
HERE=$(cd "$(dirname "$0")" && pwd)
rm -rf "$W"; mkdir -p "$W"
fail() { echo "FAIL: $*"; exit 1; }

cmake --install "$B" --prefix "$W/prefix" >"$W/install.log" 2>&1 || { cat "$W/install.log"; fail "cmake --install"; }
for f in include/probecomp/probecomp.hpp include/probecomp/compensation/pipeline.hpp lib/cmake/probecomp/probecompConfig.cmake \
         lib/cmake/probecomp/probecompConfigVersion.cmake lib/cmake/probecomp/probecompTargets.cmake bin/probecomp; do
  [ -e "$W/prefix/$f" ] || fail "not installed: $f"
done

# The README's example: the first ```cpp block after the heading "## Use it as a C++ library".
awk '/^## Use it as a C\+\+ library/{s=1} s&&/^```cpp$/{c=1; next} c&&/^```$/{exit} c{print}' "$README" >"$W/example.cpp"
[ -s "$W/example.cpp" ] || fail "no C++ example in $README"
grep -q 'probecomp/probecomp.hpp' "$W/example.cpp" || fail "the example does not include <probecomp/probecomp.hpp>"

cmake -S "$HERE/consumer" -B "$W/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$W/prefix" \
  -DEXAMPLE_SOURCE="$W/example.cpp" -DCMAKE_CXX_FLAGS="$FLAGS" -DCMAKE_EXE_LINKER_FLAGS="$FLAGS" >"$W/configure.log" 2>&1 \
  || { cat "$W/configure.log"; fail "configure the consumer"; }
cmake --build "$W/build" >"$W/build.log" 2>&1 || { cat "$W/build.log"; fail "build the README example"; }

"$W/prefix/bin/probecomp" demo --output-dir "$W/demo" >/dev/null || fail "installed probecomp demo"
"$W/build/readme_example" "$W/demo/nominal.igs" "$W/demo/raw.csv" >"$W/out.txt" 2>"$W/err.txt" || { cat "$W/err.txt"; fail "run the example"; }
cat "$W/out.txt"
"$W/prefix/bin/probecomp" --version >"$W/version.txt"
grep -q "^probecomp $(sed -n 's/^probecomp //p' "$W/version.txt"): 1 face(s), 7200 of 7200 points ok" "$W/out.txt" \
  || fail "the example's output: $(cat "$W/out.txt")"
# A failure reaches the consumer as a probecomp::Error with the file's name.
"$W/build/readme_example" "$W/demo/missing.igs" "$W/demo/raw.csv" >/dev/null 2>"$W/err.txt" && fail "a missing file must fail"
grep -q "missing.igs" "$W/err.txt" || fail "the error names the file: $(cat "$W/err.txt")"
echo "package: installed, found, built and run"
