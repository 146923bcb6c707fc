# Sourced by scripts/demo.sh and scripts/test.sh: the Release build in build/, with clang as the sanitizer build
# (scripts/sanitize_build.sh). clang compiles our Eigen-heavy templates in about half gcc's time (the fitting layer's
# unity file at -O3: 72 s against 147 s), which keeps CI within 30 minutes; the results are the same with either
# compiler (IEEE double without FMA contraction, CMakeLists.txt; the simulator's draws in a fixed order,
# simulation/random.hpp). A folder first configured with gcc is configured anew.
configure_release_build() {
  cmake -S . -B build -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release >/dev/null
}
