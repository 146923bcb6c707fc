#pragma once
// Whether this build has the x86-64 AVX code paths (PROBECOMP_HAVE_AVX_PATH) and whether this CPU runs them
// (cpu_has_avx). The bicubic evaluation (nurbs/surface.cpp) and the fit's band kernels (fitting/band.cpp) are
// compiled a second time for AVX, with the same arithmetic in the same order, and chosen at run time.

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PROBECOMP_HAVE_AVX_PATH 1
#else
#define PROBECOMP_HAVE_AVX_PATH 0
#endif

namespace probecomp::geometry {

#if PROBECOMP_HAVE_AVX_PATH
// Asked of the CPU once.
[[nodiscard]] inline bool cpu_has_avx() {
  static const bool usable = __builtin_cpu_supports("avx");
  return usable;
}
#endif

}  // namespace probecomp::geometry
