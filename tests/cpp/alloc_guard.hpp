#pragma once
// Allocation guards for the real-time tests. Include FIRST in a test binary (before any Eigen
// header), once per executable: it replaces the global operator new.
//  - eigen_assert throws (so EIGEN_RUNTIME_NO_MALLOC's check fires even under NDEBUG);
//  - a counting global operator new (plain and over-aligned: the run-time sized storage of the
//    estimators holds SIMD registers and uses C++17 aligned new; the array forms too, which the
//    sanitizers' runtimes would otherwise take over) sees every heap allocation, Eigen's or not;
//  - NoAllocationScope switches Eigen's guard off-limits and counts allocations in its scope.
#include <stdexcept>

namespace algid_test {
struct EigenAssertion : std::runtime_error {
  using std::runtime_error::runtime_error;
};
}  // namespace algid_test

#define eigen_assert(x)                                                \
  do {                                                                 \
    if (!(x)) throw ::algid_test::EigenAssertion("eigen_assert: " #x); \
  } while (0)
#define EIGEN_RUNTIME_NO_MALLOC

#include <Eigen/Dense>

#include "check.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace algid_test {
inline std::atomic<long> g_allocations{0};

struct NoAllocationScope {
  long before;
  NoAllocationScope() : before(g_allocations.load()) { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoAllocationScope() { Eigen::internal::set_is_malloc_allowed(true); }
  long allocations() const { return g_allocations.load() - before; }
};

/// Negative controls: both guards fire (call from a test; needs check.hpp's CHECK).
inline void guards_fire() {
  // The Eigen guard fires on a dynamic allocation...
  bool eigen_fired = false;
  try {
    NoAllocationScope scope;
    Eigen::MatrixXd m(4, 4);
    m.setZero();
  } catch (const algid_test::EigenAssertion&) {
    eigen_fired = true;
  }
  CHECK(eigen_fired);
  // ...and the counting operator new sees a plain new.
  long allocations = 0;
  {
    NoAllocationScope scope;
    int* volatile p = new int(3);
    allocations = scope.allocations();
    delete p;
  }
  CHECK(allocations == 1);
  {
    NoAllocationScope scope;
    double* volatile a = new double[5];
    allocations = scope.allocations();
    delete[] a;
  }
  CHECK(allocations == 1);
  // ...and an over-aligned one (aligned new, as the Dynamic estimators' storage uses).
  struct alignas(64) Wide {
    double x[8];
  };
  {
    NoAllocationScope scope;
    Wide* volatile w = new Wide[3];  // volatile: the new/delete pair may not be elided
    allocations = scope.allocations();
    delete[] w;
  }
  CHECK(allocations == 1);
}
}  // namespace algid_test

void* operator new(std::size_t size) {
  ++algid_test::g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t size, std::align_val_t align) {
  ++algid_test::g_allocations;
  const std::size_t a = static_cast<std::size_t>(align);
  const std::size_t rounded = ((size ? size : 1) + a - 1) / a * a;  // aligned_alloc: a multiple of a
  if (void* p = std::aligned_alloc(a, rounded)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void* operator new[](std::size_t size, std::align_val_t align) { return ::operator new(size, align); }
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop
