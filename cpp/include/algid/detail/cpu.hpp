#pragma once
/// @file cpu.hpp
/// Whether this CPU (and OS) runs code built for an x86-64 micro-architecture level: the
/// runtime choice between the instruction-set builds (the Python module, the tests built for
/// wider instruction sets). Not part of the estimator.

#include <cstring>

namespace algid {
namespace detail {

/// True when this CPU runs code built for `level`: "x86-64-v3" (AVX2, FMA, BMI) or
/// "x86-64-v4" (AVX-512 F/BW/CD/DQ/VL); false for other levels and architectures.
inline bool cpu_supports(const char* level) noexcept {
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
  __builtin_cpu_init();
  const bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
                  __builtin_cpu_supports("bmi2") && __builtin_cpu_supports("avx") && __builtin_cpu_supports("popcnt");
  if (std::strcmp(level, "x86-64-v3") == 0) return v3;
  if (std::strcmp(level, "x86-64-v4") == 0)
    return v3 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl");
#endif
  (void)level;
  return false;
}

}  // namespace detail
}  // namespace algid
