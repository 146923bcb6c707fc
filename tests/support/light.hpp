#pragma once
// The sanitizer build (AddressSanitizer + UndefinedBehaviorSanitizer, about ten times slower) runs a test that
// repeats one case over several seeds or sizes on its first case only: it is there for memory errors and undefined
// behaviour, which the first case exercises through the same code; every case's figures are held by the Release run
// of the same test (.ci/run runs both). PROBECOMP_TEST_LIGHT is set by tests/CMakeLists.txt.
#include <initializer_list>
#include <vector>

namespace probecomp::test {

#ifdef PROBECOMP_TEST_LIGHT
inline constexpr bool kLight = true;
#else
inline constexpr bool kLight = false;
#endif

// `all` in the Release build, its first element in the sanitizer build.
template <class T>
[[nodiscard]] std::vector<T> cases(std::initializer_list<T> all) {
  if (kLight) return {*all.begin()};
  return all;
}

}  // namespace probecomp::test
