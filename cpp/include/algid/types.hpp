#pragma once
/// @file types.hpp
/// Alias templates, enums and the configuration-error helper shared by every algid header.

#include <Eigen/Core>

#include <cstdlib>
#include <stdexcept>

/// Marks a per-sample kernel whose callees (Eigen's expression evaluators, the lane helpers)
/// must all be inlined into it: GCC and Clang stop inlining them once a translation unit
/// instantiates many chain sizes, and a call per 8-lane operation costs more than the
/// operation. Expands to nothing on other compilers.
#if defined(__GNUC__) || defined(__clang__)
#define ALGID_FLATTEN __attribute__((flatten))
#else
#define ALGID_FLATTEN
#endif

namespace algid {

/// A size known only at run time (Eigen's Dynamic): ChainEstimator<Dynamic> takes the number of
/// DOF in its configuration phase.
inline constexpr int Dynamic = Eigen::Dynamic;

/// Column vector (fixed size, or Dynamic).
template <class Scalar, int Rows>
using Vector = Eigen::Matrix<Scalar, Rows, 1>;

/// Matrix (column-major).
template <class Scalar, int Rows, int Cols>
using Matrix = Eigen::Matrix<Scalar, Rows, Cols>;

/// What lies beyond the last mass of the chain.
enum class Boundary {
  kFixed,  ///< a wall: spring n+1 joins DOF n to ground and k_{n+1} is identified (the paper)
  kFree,   ///< no wall: k_{n+1} = 0 is known and DOF n solves a 3x3 system
};

/// Result of one per-sample `update()`.
enum class Status {
  kOk = 0,        ///< sample consumed; see the per-DOF validity flags for the estimates
  kWarmup = 1,    ///< sample consumed, but the quadrature stencil is not full yet (no estimate)
  kBadInput = 2,  ///< a non-finite sample, or one whose integrals overflow: the estimator reseeded
  kDropout = 3,   ///< ContinuousEstimator: an acceleration stuck or clipped (detail/dropout.hpp): discarded
};

namespace detail {

/// Configuration errors: thrown where exceptions exist, a hard stop where they do not
/// (firmware built with -fno-exceptions calls the non-throwing `validate()` first).
[[noreturn]] inline void config_error(const char* what) {
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
  throw std::invalid_argument(what);
#else
  (void)what;
  std::abort();
#endif
}

/// 1 / x for a scalar or, lane by lane, for an Eigen array (the same IEEE division).
template <class Scalar>
inline Scalar reciprocal(Scalar x) noexcept {
  return Scalar(1) / x;
}
template <class Scalar, int B>
inline Eigen::Array<Scalar, B, 1> reciprocal(const Eigen::Array<Scalar, B, 1>& x) noexcept {
  return x.inverse();
}

}  // namespace detail
}  // namespace algid
