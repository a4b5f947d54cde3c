#pragma once
/// @file ratio_estimator.hpp
/// The ratio estimator of eq. 7: theta_j = I^2 |Delta_j| / I^2 |Delta| (double integrals
/// from t_0 of the Cramer determinants).
///
/// Implemented as I^2( sgn(Delta) Delta_j ) / I^2 |Delta|, i.e. the |Delta|-weighted mean of
/// the instantaneous Cramer solutions; for the positive parameters of eq. 1 it equals the
/// paper's ratio, and it stays unbiased for a parameter that is zero or negative.
///
/// Scaling: |Delta| of the physical system grows like tau^q (q = 19 for 4x4, 12 for 3x3; 14 and
/// 8 for the homogeneous system of a DOF without force, see ChainEstimator), which
/// spans hundreds of decades over a window and overflows single precision. The double
/// integrals are therefore kept multiplied by tau^-q; a common factor cancels in the ratio, so
/// the weights fed in are the determinants of the time-scaled system (order one), and each
/// step rescales the states by (tau_prev / tau)^q. Double integration is trapezoidal: its
/// weights are the same for numerator and denominator, so a constant theta is reproduced exactly.

#include "algid/detail/lanes.hpp"
#include "algid/types.hpp"

namespace algid {

/// Power of (t - t0) that relates |det A| of an M x M system of eq. 5 to the determinant of the
/// time-scaled system (19 for 4x4, 12 for 3x3).
template <int M>
inline constexpr int kTimeExponent = M == 4 ? 19 : 12;

/// The same power for the homogeneous system of a DOF without force (ChainEstimator), whose
/// equation determines only ratios to its mass: rows 0-2 of eq. 5, columns c_i, k_i, k_{i+1}
/// (14, in a DOF of a 4x4 system), or rows 0-1 and columns c_n, k_n (8, the last DOF at a free
/// end, a 3x3 system).
template <int M>
inline constexpr int kRatioTimeExponent = M == 4 ? 14 : 8;

/// (prev_tau / tau)^Q by repeated squaring (0 from prev_tau = 0). @realtime no allocation, no throw
template <int Q, class T>
inline T decay_power(const T& prev_tau, const T& tau) noexcept {
  static_assert(Q >= 1, "a positive power");
  T ratio = prev_tau / tau;
  // the first factor is taken as it is (1 * x == x exactly)
  T rho = ratio;
  bool first = true;
  for (int e = Q; e > 0; e >>= 1) {
    if (e & 1) {
      rho = first ? ratio : T(rho * ratio);
      first = false;
    }
    ratio = ratio * ratio;
  }
  return rho;
}

/// Factor (prev_tau / tau)^q, q = kTimeExponent<M>, that carries the tau^-q-scaled states of eq.
/// 7 from prev_tau to tau (0 from prev_tau = 0, i.e. at the first sample of a window). The same
/// for every DOF of a chain: computed once per sample. @realtime no allocation, no throw
template <int M, class T>
inline T ratio_decay(const T& prev_tau, const T& tau) noexcept {
  static_assert(M == 3 || M == 4, "eq. 5 systems are 3x3 or 4x4");
  return decay_power<kTimeExponent<M>>(prev_tau, tau);
}

/// The factor of ratio_decay for the homogeneous system of a DOF without force,
/// q = kRatioTimeExponent<M>. @realtime no allocation, no throw
template <int M, class T>
inline T homogeneous_decay(const T& prev_tau, const T& tau) noexcept {
  static_assert(M == 3 || M == 4, "eq. 5 systems are 3x3 or 4x4");
  return decay_power<kRatioTimeExponent<M>>(prev_tau, tau);
}

/// Eq. 7 of W DOF side by side, one per SIMD lane (the layout of ChainEstimator), for the M
/// parameters of their M x M systems; a 3x3 DOF among 4x4 ones has 0 in its fourth numerator
/// and its own decay factor in its lane. Per lane, the trapezoidal double integrals of |Delta|
/// and of the M sgn(Delta) Delta_j, scaled as in the file comment.
template <class Scalar, int W, int M = 4>
class RatioLanes {
 public:
  using L = detail::Lanes<Scalar, W>;

  /// Start a new window. @realtime no allocation, no throw
  void reset() noexcept {
    for (int j = 0; j < kIntegrals; ++j) {
      i1_[j].setZero();
      i2_[j].setZero();
      prev_[j].setZero();
    }
  }

  /// Add the sample at the next interval end: `rho` = ratio_decay<M>(previous tau, tau) of
  /// each lane's M, `half` = h / 2 [s], `weight` = |det S| (0 where not trusted) and
  /// `weighted[j]` = weight * theta_instant_j (0 where not trusted).
  /// @realtime no allocation, no throw
  void add(const L& rho, Scalar half, const L& weight, const L* weighted) noexcept {
    using Ops = detail::LaneOps<Scalar, W>;
    const L h = L::Constant(half);
    for (int j = 0; j < kIntegrals; ++j) {
      const L& x = j == 0 ? weight : weighted[j - 1];
      const L i1 = Ops::madd(rho, Ops::madd(h, prev_[j], i1_[j]), half * x);
      i2_[j] = Ops::madd(rho, Ops::madd(h, i1_[j], i2_[j]), half * i1);
      i1_[j] = i1;
      prev_[j] = x;
    }
  }

  /// Start a new window in the lanes where `mask` > 0 (a DOF whose force has just appeared:
  /// its system changes). @realtime no allocation, no throw
  void restart(const L& mask) noexcept {
    using Ops = detail::LaneOps<Scalar, W>;
    const L zero = L::Zero();
    for (int j = 0; j < kIntegrals; ++j) {
      i1_[j] = Ops::if_less(zero, mask, zero, i1_[j]);
      i2_[j] = Ops::if_less(zero, mask, zero, i2_[j]);
      prev_[j] = Ops::if_less(zero, mask, zero, prev_[j]);
    }
  }

  /// Scaled I^2|Delta| of every lane: a lane's estimate is valid where it is > 0.
  const L& denominator() const noexcept { return i2_[0]; }
  /// Scaled I^2(sgn(Delta) Delta_j) of every lane, j = 0 .. M - 1 (contiguous).
  const L* numerators() const noexcept { return &i2_[1]; }

 private:
  static constexpr int kIntegrals = M + 1;  // |Delta| and the M numerators
  // I^1, I^2 and the last sample of [|Delta|, sgn(Delta) Delta_1 .. Delta_M], lane by lane
  L i1_[kIntegrals], i2_[kIntegrals], prev_[kIntegrals];
};

}  // namespace algid
