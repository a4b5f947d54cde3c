#pragma once
/// @file integrator_chain.hpp
/// The iterated integrator chains of eqs. 4 and 6 for one measured signal.
///
/// For a signal f sampled at t_k = t_0 + k h the chain keeps, at the interval end t_{j+1},
///
///   G(p, r) = I^r( Delta^p f )(t_{j+1}),   p = 0, 1, 2,   r = 0 .. 5,   Delta = t - t_0,
///
/// with I^0 the sample itself and I^r the r-fold integral from t_0 (zero initial conditions,
/// eq. 6). These are all the signals eqs. 4-6 combine into the 4x4 system of one DOF.
/// The interpolatory rule needs P samples around each interval, so the chain reports the
/// instant t_{j+1} = t_k - (P-2) h when sample k arrives.

#include "algid/quadrature.hpp"
#include "algid/types.hpp"

namespace algid {

/// Integrator chains of one signal. Storage: a (2 * 2P) x 3 ring of Delta^p f samples, a
/// 5 x 3 state and its 5 x 3 Kahan compensation (used in single precision); nothing else. Do not build with -ffast-math
/// (it would remove the compensation).
/// @tparam P interpolation points of the quadrature (see InterpolatoryRule).
template <int P, class Scalar = double>
class IntegratorChain {
 public:
  /// Highest order of iterated integral kept (row 4 of eq. 5 needs I^3 of the I^2 in eq. 4).
  static constexpr int kOrders = 5;
  /// Powers of Delta the signals are multiplied by (eq. 4 needs Delta^0..Delta^2).
  static constexpr int kPowers = 3;
  /// Kahan-compensated state update: on for single precision (where the state, growing like
  /// tau^(r+p), otherwise loses the small per-step increments), off for double.
  static constexpr bool kCompensated = sizeof(Scalar) < sizeof(double);
  /// The rule this chain is advanced with.
  using Rule = InterpolatoryRule<P, kOrders, Scalar>;

  /// Forget everything: the next sample is t_0. @realtime no allocation, no throw.
  void reset() noexcept {
    count_ = 0;
    state_.setZero();
    value_.setZero();
  }

  /// Consume sample f_k taken at Delta_k = k h [s] from t_0. Returns true when the chain has
  /// advanced to a new interval end (from the P-th sample on). @realtime no allocation, no throw.
  bool push(Scalar f, Scalar delta, const Rule& rule) noexcept {
    const int slot = static_cast<int>(count_ % kRing);
    const Scalar g[kPowers] = {f, delta * f, delta * delta * f};
    for (int p = 0; p < kPowers; ++p) {
      ring_(slot, p) = g[p];
      ring_(slot + kRing, p) = g[p];  // doubled ring: any stencil is a contiguous block
    }
    ++count_;
    if (count_ < P) return false;
    const long j = count_ - P;                         // interval [t_j, t_{j+1}]
    const long start = j - (P / 2 - 1) > 0 ? j - (P / 2 - 1) : 0;  // centred, shifted near t_0
    const int off = static_cast<int>(j - start);
    const int first = static_cast<int>(start % kRing);
    Matrix<Scalar, kOrders, kPowers> increment;
    increment.noalias() = rule.weights(off) * ring_.template block<P, kPowers>(first, 0);
    // I^r += sum_{q<r} h^(r-q)/(r-q)! I^q + increment: the propagation is unit lower
    // triangular, so update in place from the highest order down (the lower orders are still
    // the old ones), with Kahan compensation: the state grows like tau^(r+p) while each step
    // adds a small amount, which is where single precision loses its digits.
    // (Double precision keeps its digits without the compensation: it is skipped there.)
    const auto& prop = rule.propagate();
    for (int p = 0; p < kPowers; ++p) {
      for (int r = kOrders - 1; r >= 0; --r) {
        Scalar step = increment(r, p);
        for (int q = 0; q < r; ++q) step += prop(r, q) * state_(q, p);
        if constexpr (kCompensated) {
          const Scalar y = step - compensation_(r, p);
          const Scalar t = state_(r, p) + y;
          compensation_(r, p) = (t - state_(r, p)) - y;
          state_(r, p) = t;
        } else {
          state_(r, p) += step;
        }
      }
    }
    const int end = static_cast<int>((j + 1) % kRing);
    value_ = ring_.row(end).transpose();
    return true;
  }

  /// I^r(Delta^p f) at the current interval end; r = 0 is the sample value itself.
  Scalar operator()(int p, int r) const noexcept { return r == 0 ? value_(p) : state_(r - 1, p); }

  /// Samples consumed since the last reset.
  long count() const noexcept { return count_; }

 private:
  static constexpr int kRing = 2 * P;  // >= 3P/2 - 1 samples: a centred stencil's span
  Matrix<Scalar, 2 * kRing, kPowers> ring_ = Matrix<Scalar, 2 * kRing, kPowers>::Zero();
  Matrix<Scalar, kOrders, kPowers> state_ = Matrix<Scalar, kOrders, kPowers>::Zero();
  Matrix<Scalar, kOrders, kPowers> compensation_ = Matrix<Scalar, kOrders, kPowers>::Zero();  // Kahan
  Vector<Scalar, kPowers> value_ = Vector<Scalar, kPowers>::Zero();
  long count_ = 0;
};

}  // namespace algid
