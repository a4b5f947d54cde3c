#pragma once
// Minimal assertion harness for the C++ tests (no third-party test framework to install).
// Each binary prints "N passed, N failed" and exits non-zero on any failure.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#ifdef ALGID_TEST_REQUIRES_ISA
#include <algid/detail/cpu.hpp>
#endif

namespace algid_test {
inline int& passed() {
  static int n = 0;
  return n;
}
inline int& failed() {
  static int n = 0;
  return n;
}
inline void record(bool ok, const char* what, const char* file, int line) {
  if (ok) {
    ++passed();
  } else {
    ++failed();
    std::printf("FAIL %s:%d: %s\n", file, line, what);
  }
}
inline int finish(const char* name) {
  std::printf("%s: %d passed, %d failed\n", name, passed(), failed());
  return failed() == 0 ? 0 : 1;
}

#ifdef ALGID_TEST_REQUIRES_ISA
// A test binary built for a wider instruction set: exit 77 (skipped) before main where this CPU
// cannot run it.
inline const bool kCpuRunsThisBuild = [] {
  if (!algid::detail::cpu_supports(ALGID_TEST_REQUIRES_ISA)) {
    std::printf("skipped: this CPU does not run %s code\n", ALGID_TEST_REQUIRES_ISA);
    std::exit(77);
  }
  return true;
}();
#endif
}  // namespace algid_test

#define CHECK(cond) ::algid_test::record(static_cast<bool>(cond), #cond, __FILE__, __LINE__)
#define CHECK_NEAR(a, b, tol)                                                                                    \
  do {                                                                                                           \
    const double check_a_ = static_cast<double>(a), check_b_ = static_cast<double>(b);                           \
    const bool check_ok_ = std::abs(check_a_ - check_b_) <= static_cast<double>(tol);                            \
    if (!check_ok_)                                                                                              \
      std::printf("  %s = %.17g, %s = %.17g, tol %.3g\n", #a, check_a_, #b, check_b_, static_cast<double>(tol)); \
    ::algid_test::record(check_ok_, #a " ~ " #b, __FILE__, __LINE__);                                            \
  } while (0)
