#pragma once
/// @file quadrature.hpp
/// Interpolatory weights for advancing iterated integrals over one sample interval.
///
/// On the interval [t_j, t_{j+1}] the sampled signal is replaced by the polynomial of degree
/// P-1 through P consecutive samples t_{j-off} .. t_{j-off+P-1}; the r-fold iterated integral
/// from t_0 is then advanced exactly for that polynomial:
///
///   I^r(t_{j+1}) = sum_{q=1..r} h^(r-q)/(r-q)! I^q(t_j)
///                + h^r sum_m W[off](r-1, m) f_{j-off+m},
///   W[off](r-1, m) = int_0^1 (1-x)^(r-1)/(r-1)! L_m(off + x) dx,
///
/// where L_m is the Lagrange basis on the nodes 0..P-1. The rule is exact for polynomial
/// signals of degree P-1, and its global error is O(h^P). The stencil is centred on the
/// interval (off = P/2-1) except near t_0, where it is shifted right (off = 0..P/2-2) so that
/// the start-up uses the same order: no low-order first steps.

#include "algid/detail/lanes.hpp"
#include "algid/types.hpp"

#include <array>

namespace algid {

/// Precomputed weights of the interpolatory rule with `P` points for orders 1..`Orders`.
/// @tparam P number of interpolation points (even, >= 2); P = 2 is piecewise linear.
/// @tparam Orders highest iterated-integral order advanced.
template <int P, int Orders, class Scalar = double>
class InterpolatoryRule {
  static_assert(P >= 2 && P % 2 == 0, "P must be even and >= 2");
  static_assert(Orders >= 1, "at least one integration order");

 public:
  /// Stencil offsets that occur: off = 0 .. P/2 - 1.
  static constexpr int kOffsets = P / 2;
  /// Samples the estimate lags behind the newest sample (the start-up needs a full stencil).
  static constexpr int kDelay = P - 2;

  /// First sample of the stencil of interval [t_j, t_{j+1}]: centred, shifted right near t_0
  /// (its offset `j - stencil_start(j)` selects the weights).
  static constexpr long stencil_start(long j) noexcept { return j - (P / 2 - 1) > 0 ? j - (P / 2 - 1) : 0; }

  InterpolatoryRule() = default;

  /// Weights scaled for a sample period `h` [s]. May be called in the configuration phase only.
  explicit InterpolatoryRule(Scalar h) { configure(h); }

  /// Recompute for sample period `h` [s]; no allocation.
  void configure(Scalar h) noexcept {
    for (int off = 0; off < kOffsets; ++off) {
      const auto w = unit_weights(off);
      for (int r = 0; r < Orders; ++r) {
        long double hr = 1.0L;
        for (int e = 0; e <= r; ++e) hr *= static_cast<long double>(h);
        for (int m = 0; m < P; ++m) weights_[off](r, m) = static_cast<Scalar>(hr * w[r][m]);
      }
    }
    // Exact carry of the lower orders over one interval (Taylor): strictly lower triangular.
    carry_.setZero();
    for (int r = 1; r < Orders; ++r) {
      long double term = static_cast<long double>(h);
      for (int q = r - 1; q >= 0; --q) {
        carry_(r, q) = static_cast<Scalar>(term);
        term *= static_cast<long double>(h) / static_cast<long double>(r - q + 1);
      }
    }
  }

  /// `h^r W[off](r-1, m)` as an Orders x P matrix.
  const Matrix<Scalar, Orders, P>& weights(int off) const noexcept { return weights_[off]; }

  /// Strictly lower-triangular Orders x Orders matrix `h^(r-q)/(r-q)!` (q < r): what the lower
  /// orders add to I^r over one interval, I^r(t+h) = I^r(t) + sum_q carry(r, q) I^q(t) + h^r W f.
  const Matrix<Scalar, Orders, Orders>& carry() const noexcept { return carry_; }

  /// Unscaled weights (h = 1) in long double: `W[off](r, m)`, r = 0 .. Orders-1.
  static std::array<std::array<long double, P>, Orders> unit_weights(int off) noexcept {
    std::array<std::array<long double, P>, Orders> out{};
    for (int m = 0; m < P; ++m) {
      // Coefficients of L_m(off + x) in powers of x (degree P-1).
      std::array<long double, P> basis{};
      basis[0] = 1.0L;
      int degree = 0;
      long double denom = 1.0L;
      for (int node = 0; node < P; ++node) {
        if (node == m) continue;
        // multiply by (x + off - node)
        const long double shift = static_cast<long double>(off - node);
        for (int d = degree + 1; d >= 1; --d) basis[d] = basis[d - 1] + shift * basis[d];
        basis[0] *= shift;
        ++degree;
        denom *= static_cast<long double>(m - node);
      }
      for (auto& b : basis) b /= denom;
      // int_0^1 (1-x)^r / r! x^d dx = d! / (r + d + 1)!  (Beta function)
      for (int r = 0; r < Orders; ++r) {
        long double sum = 0.0L;
        for (int d = 0; d < P; ++d) sum += basis[d] * beta_factorial(r, d);
        out[r][m] = sum;
      }
    }
    return out;
  }

 private:
  static long double beta_factorial(int r, int d) noexcept {
    // d! / (r + d + 1)!
    long double v = 1.0L;
    for (int i = d + 1; i <= r + d + 1; ++i) v /= static_cast<long double>(i);
    return v;
  }

  std::array<Matrix<Scalar, Orders, P>, kOffsets> weights_{};
  Matrix<Scalar, Orders, Orders> carry_ = Matrix<Scalar, Orders, Orders>::Zero();
};

/// The weights of an InterpolatoryRule with every value repeated across W lanes, for the lane
/// layout of the integrator chains (IntegratorLanes): a lane update then multiplies by a weight
/// straight from memory. Storage: (P/2 P + Orders) Orders lanes (7 KiB for P = 8, 7 orders and 4
/// lanes of double).
template <int P, int Orders, class Scalar, int W>
class LaneWeights {
 public:
  using Rule = InterpolatoryRule<P, Orders, Scalar>;
  using L = detail::Lanes<Scalar, W>;

  /// Copy the weights of `rule`. May be called in the configuration phase only.
  void configure(const Rule& rule) noexcept {
    for (int off = 0; off < Rule::kOffsets; ++off)
      for (int r = 0; r < Orders; ++r)
        for (int m = 0; m < P; ++m) weights_[off][r][m] = L::Constant(rule.weights(off)(r, m));
    for (int r = 0; r < Orders; ++r)
      for (int q = 0; q < Orders; ++q) carry_[r][q] = L::Constant(rule.carry()(r, q));
  }

  /// `h^(r+1) W[off](r, m)` in every lane, r = 0 .. Orders-1 (order r + 1).
  const L& weight(int off, int r, int m) const noexcept { return weights_[off][r][m]; }
  /// `carry(r, q)` of the rule in every lane.
  const L& carry(int r, int q) const noexcept { return carry_[r][q]; }

 private:
  std::array<std::array<std::array<L, P>, Orders>, Rule::kOffsets> weights_{};
  std::array<std::array<L, Orders>, Orders> carry_{};
};

}  // namespace algid
