# Sourced by scripts/test.sh --sanitize and scripts/fuzz.sh: the one instrumented build, build-sanitize/, and the
# sanitizers' settings. clang, AddressSanitizer and UndefinedBehaviorSanitizer at -O2 (CMakeLists.txt), and the
# fuzz targets (-DPROBECOMP_FUZZ=ON: libFuzzer's coverage in the readers' layers): the tests and the fuzz targets link
# the same instrumented library, compiled once (CI within 30 minutes; clang also compiled our template-heavy files in
# two thirds of gcc's time). No Python package: the interpreter would have to preload the sanitizers' runtime to load
# it. A unity build, as every build by default (CMakeLists.txt).
sanitize_build_dir=build-sanitize
configure_sanitize_build() {
  # The compiler named, not taken from CXX: CXX is read only when a build folder is first configured.
  cmake -S . -B "$sanitize_build_dir" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug -DPROBECOMP_SANITIZE=ON \
    -DPROBECOMP_FUZZ=ON -DPROBECOMP_BUILD_BENCH=OFF -DPROBECOMP_BUILD_PYTHON=OFF >/dev/null
}
# Stop at the first report, leaks included.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}"
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
