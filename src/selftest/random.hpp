#pragma once
// splitmix64 (Steele, Lea, Flood 2014) for the self-test's data: the same numbers on every platform and standard
// library, unlike the standard distributions, whose algorithms are left to the implementation.

#include <cstdint>

namespace probecomp::selftest {

struct Random {
  std::uint64_t state;
  double uniform() {  // in [0, 1)
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }
  double between(double a, double b) { return a + (b - a) * uniform(); }
};

}  // namespace probecomp::selftest
