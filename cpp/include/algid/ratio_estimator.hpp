#pragma once
/// @file ratio_estimator.hpp
/// The ratio estimator of eq. 7: theta_j = I^2 |Delta_j| / I^2 |Delta| (double integrals
/// from t_0 of the Cramer determinants).
///
/// Implemented as I^2( sgn(Delta) Delta_j ) / I^2 |Delta|, i.e. the |Delta|-weighted mean of
/// the instantaneous Cramer solutions; for the positive parameters of eq. 1 it equals the
/// paper's ratio, and it stays unbiased for a parameter that is zero or negative.
///
/// Scaling: |Delta| of the physical system grows like tau^q (q = 19 for 4x4, 12 for 3x3), which
/// spans hundreds of decades over a window and overflows single precision. The double
/// integrals are therefore kept multiplied by tau^-q; a common factor cancels in the ratio, so
/// the weights fed in are the determinants of the time-scaled system (order one), and each
/// step rescales the states by (tau_prev / tau)^q. Double integration is trapezoidal: its
/// weights are the same for numerator and denominator, so a constant theta is reproduced exactly.

#include "algid/detail/lanes.hpp"
#include "algid/types.hpp"

namespace algid {

/// Eq. 7 for an M x M system. @tparam M 4 (full DOF) or 3 (reduced DOF).
template <int M, class Scalar = double>
class RatioEstimator {
  static_assert(M == 3 || M == 4, "eq. 5 systems are 3x3 or 4x4");

 public:
  /// Power of (t - t0) that relates |det A| to the determinant of the time-scaled system.
  static constexpr int kTimeExponent = M == 4 ? 19 : 12;

  /// |Delta| and the M numerators side by side (slot 0: |Delta|, slot 1 + j: numerator j),
  /// padded with zeros to whole SIMD registers of four: one vector recurrence advances them all.
  static constexpr int kSlots = M + 1 <= 4 ? 4 : 8;
  using Packed = Vector<Scalar, kSlots>;

  /// Start a new window. @realtime no allocation, no throw
  void reset() noexcept {
    i1_.setZero();
    i2_.setZero();
    prev_.setZero();
  }

  /// Factor (prev_tau / tau)^q that carries the tau^-q-scaled states from prev_tau to tau
  /// (0 from prev_tau = 0, i.e. at the first sample of a window). The same for every DOF of a
  /// chain: compute it once per sample. @realtime no allocation, no throw
  /// Also lane by lane for Eigen arrays of instants (the same operations, the same bits).
  template <class T>
  static T decay(const T& prev_tau, const T& tau) noexcept {
    T ratio = prev_tau / tau;
    // ratio^q by repeated squaring (q is a small compile-time constant > 0); the first factor
    // is taken as it is (1 * x == x exactly).
    T rho = ratio;
    bool first = true;
    for (int e = kTimeExponent; e > 0; e >>= 1) {
      if (e & 1) {
        if (!first) rho = rho * ratio;
        first = false;
      }
      ratio = ratio * ratio;
    }
    return rho;
  }

  /// Add the sample at tau = t - t0 with sample period `h` [s]: `x` = [weight, weighted_0 ..
  /// weighted_(M-1), 0 ...] with weight = |det S| and weighted = weight * theta_instant (all 0
  /// for a sample that is not trusted); `rho` = decay(previous tau, tau) carries the scaled
  /// states from the previous sample. @realtime no allocation, no throw
  void add(Scalar rho, Scalar h, const Packed& x) noexcept {
    const Scalar half = Scalar(0.5) * h;
    const Packed i1 = rho * (i1_ + half * prev_) + half * x;
    i2_ = rho * (i2_ + half * i1_) + half * i1;
    i1_ = i1;
    prev_ = x;
  }

  /// True once a trusted sample has entered the double integral.
  bool valid() const noexcept { return i2_(0) > Scalar(0); }

  /// Eq. 7 estimate of parameter j (meaningful only when valid()).
  Scalar estimate(int j) const noexcept { return i2_(1 + j) / i2_(0); }

  /// All M eq. 7 estimates at once (one division), in slots 1 .. M (slot 0 is
  /// I^2|Delta| / I^2|Delta|).
  Packed packed_estimates() const noexcept { return i2_ * (Scalar(1) / i2_(0)); }

  /// All M eq. 7 estimates at once (one division).
  Vector<Scalar, M> estimates() const noexcept { return packed_estimates().template segment<M>(1); }

  /// The scaled double integrals [I^2 |Delta|, I^2 sgn(Delta) Delta_0 .. Delta_(M-1), 0 ...]
  /// * tau^-q, whose ratios are the estimates.
  const Packed& integrals() const noexcept { return i2_; }

  /// Scaled denominator I^2|Delta| * tau^-q (a confidence weight for fusion and diagnostics).
  Scalar denominator() const noexcept { return i2_(0); }

 private:
  // I^1, I^2 and the last sample of [|Delta|, sgn(Delta) Delta_j ...]
  Packed i1_ = Packed::Zero(), i2_ = Packed::Zero(), prev_ = Packed::Zero();
};

/// Eq. 7 of W DOF side by side, one per SIMD lane (the lane layout of ChainEstimator), for
/// the four parameters of a 4x4 system; a DOF with a 3x3 system has 0 in its fourth numerator,
/// and its own decay factor in its lane. Per lane, the trapezoidal double integrals of
/// RatioEstimator with the same scaling, for |Delta| and the four sgn(Delta) Delta_j alike.
template <class Scalar, int W>
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

  /// Add the sample at the next interval end: `rho` = RatioEstimator<M>::decay(previous tau,
  /// tau) of each lane's M, `half` = h / 2 [s], `weight` = |det S| (0 where not trusted) and
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

  /// Scaled I^2|Delta| of every lane: a lane's estimate is valid where it is > 0.
  const L& denominator() const noexcept { return i2_[0]; }
  /// Scaled I^2(sgn(Delta) Delta_j) of every lane, j = 0 .. 3 (contiguous).
  const L* numerators() const noexcept { return &i2_[1]; }

 private:
  static constexpr int kIntegrals = 5;  // |Delta| and the four numerators
  // I^1, I^2 and the last sample of [|Delta|, sgn(Delta) Delta_1 .. Delta_4], lane by lane
  L i1_[kIntegrals], i2_[kIntegrals], prev_[kIntegrals];
};

}  // namespace algid
