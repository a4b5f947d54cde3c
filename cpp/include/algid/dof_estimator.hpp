#pragma once
/// @file dof_estimator.hpp
/// One DOF of eq. 3: builds the time-scaled system of eq. 5 from the integrator chains of
/// its own acceleration, its neighbours' accelerations and its force, solves it by Cramer's
/// rule and feeds the ratio estimator of eq. 7.
///
/// Time scaling (exact, it only changes units): with tau = t - t0,
///   S = diag(1, tau^-1, tau^-2, tau^-3) A diag(tau^-2, tau^-3, tau^-4, tau^-4),
///   s = tau^-2 diag(1, tau^-1, tau^-2, tau^-3) B,
///   S phi = s,   theta = [phi_1, phi_2 / tau, phi_3 / tau^2, phi_4 / tau^2],
/// so every entry of S is of the order of the accelerations whatever tau is.
///
/// Validity rule: a sample is *trusted* when (i) at least `min_samples` samples have been
/// consumed since t0, (ii) det S is finite and non-zero, and (iii) the Hadamard ratio of S
/// after scaling every column and then every row to unit norm, |det| / prod(norms), is at
/// least `min_hadamard` (1 for orthogonal columns, 0 for a singular system: it catches the
/// structurally singular cases, e.g. a constant force since t0, for which B = 0). Only trusted
/// samples enter eq. 7, and the eq. 7 estimate is valid once one has.

#include "algid/cramer.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/ratio_estimator.hpp"
#include "algid/types.hpp"

#include <cmath>
#include <limits>

namespace algid {

/// Per-DOF thresholds of the validity rule.
template <class Scalar>
struct ValidityRule {
  int min_samples = 16;                  ///< samples since t0 before any estimate is trusted
  Scalar min_hadamard = Scalar(1e-9);    ///< lowest doubly equilibrated Hadamard ratio trusted
};

/// Estimator of theta_i = [m_i, c_i, k_i, k_{i+1}] for one DOF.
/// @tparam M 4 (the paper) or 3 (k_{i+1} known to be zero, or n = 1 where only k_1 + k_2 is
/// identifiable: then theta = [m, c, k_1 + k_2]).
template <int M, class Scalar = double>
class DofEstimator {
 public:
  /// Start a new window. @realtime no allocation, no throw
  void reset() noexcept {
    ratio_.reset();
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    instant_.setConstant(nan);
    hadamard_ = Scalar(0);
    trusted_ = false;
  }

  /// Advance to the interval end tau = t - t0 [s]. `left` and `right` are the neighbours'
  /// acceleration chains (nullptr at a wall), `self` this DOF's, `force` its force chain.
  /// @realtime no allocation, no throw
  template <class Chain>
  void update(const Chain* left, const Chain& self, const Chain* right, const Chain& force, Scalar tau,
              Scalar h, long samples, const ValidityRule<Scalar>& rule) noexcept {
    const Scalar inv = Scalar(1) / tau;
    const Scalar inv2 = inv * inv;
    const Scalar inv3 = inv2 * inv;
    const Scalar inv4 = inv2 * inv2;
    Scalar row_scale = Scalar(1);
    for (int q = 0; q < M; ++q) {
      // eq. 4 (row 1) and its q-fold integrals (eq. 6)
      const Scalar a_m = self(2, q) - Scalar(4) * self(1, q + 1) + Scalar(2) * self(0, q + 2);
      const Scalar a_c = self(2, q + 1) - Scalar(2) * self(1, q + 2);
      const Scalar a_k = self(2, q + 2) - (left ? (*left)(2, q + 2) : Scalar(0));
      const Scalar b = force(2, q) - Scalar(4) * force(1, q + 1) + Scalar(2) * force(0, q + 2);
      system_(q, 0) = a_m * row_scale * inv2;
      system_(q, 1) = a_c * row_scale * inv3;
      system_(q, 2) = a_k * row_scale * inv4;
      if constexpr (M == 4) {
        const Scalar a_k1 = self(2, q + 2) - (right ? (*right)(2, q + 2) : Scalar(0));
        system_(q, 3) = a_k1 * row_scale * inv4;
      }
      rhs_(q) = b * row_scale * inv2;
      row_scale *= inv;
    }
    const CramerSolution<Scalar, M> sol = cramer(system_, rhs_);
    hadamard_ = equilibrated_hadamard(sol.det);
    Vector<Scalar, M> unscale;
    unscale(0) = Scalar(1);
    unscale(1) = inv;
    unscale(2) = inv2;
    if constexpr (M == 4) unscale(3) = inv2;
    const bool solvable = std::isfinite(sol.det) && sol.det != Scalar(0);
    trusted_ = solvable && samples >= rule.min_samples && hadamard_ >= rule.min_hadamard;
    if (solvable) {
      instant_ = sol.numerator.cwiseProduct(unscale) * (Scalar(1) / sol.det);
    } else {
      instant_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
    }
    if (trusted_) {
      const Scalar sign = sol.det > Scalar(0) ? Scalar(1) : Scalar(-1);
      ratio_.add(tau, h, std::abs(sol.det), sign * sol.numerator.cwiseProduct(unscale));
    } else {
      ratio_.add(tau, h, Scalar(0), Vector<Scalar, M>::Zero());
    }
  }

  /// Instantaneous Cramer solution of eq. 5 at the last update (NaN if singular).
  const Vector<Scalar, M>& instant() const noexcept { return instant_; }
  /// True if the last sample was trusted (see the validity rule).
  bool instant_valid() const noexcept { return trusted_; }
  /// Eq. 7 estimate of parameter j; meaningful when valid().
  Scalar estimate(int j) const noexcept { return ratio_.estimate(j); }
  /// All eq. 7 estimates; meaningful when valid().
  Vector<Scalar, M> estimates() const noexcept { return ratio_.estimates(); }
  /// True once eq. 7 has integrated a trusted sample.
  bool valid() const noexcept { return ratio_.valid(); }
  /// Doubly equilibrated Hadamard ratio of the last system, in [0, 1].
  Scalar hadamard() const noexcept { return hadamard_; }
  /// The last time-scaled system S and right-hand side s.
  const Matrix<Scalar, M, M>& system() const noexcept { return system_; }
  const Vector<Scalar, M>& rhs() const noexcept { return rhs_; }
  /// Eq. 7's accumulated weight (scaled), for fusion.
  Scalar weight() const noexcept { return ratio_.denominator(); }

 private:
  // |det| / prod(column norms) / prod(norms of the rows of the column-normalised matrix),
  // with M reciprocals and three square roots (columns paired so that no product of squared
  // norms leaves the range of single precision; normalised rows have squared norms <= M).
  Scalar equilibrated_hadamard(Scalar det) const noexcept {
    Vector<Scalar, M> inv_col2;
    for (int c = 0; c < M; ++c) {
      const Scalar col2 = system_.col(c).squaredNorm();
      if (!(col2 > Scalar(0))) return Scalar(0);
      inv_col2(c) = Scalar(1) / col2;
    }
    Scalar row_product = Scalar(1);
    for (int r = 0; r < M; ++r) {
      Scalar row2 = Scalar(0);
      for (int c = 0; c < M; ++c) row2 += system_(r, c) * system_(r, c) * inv_col2(c);
      row_product *= row2;
    }
    const Scalar tail = M == 4 ? inv_col2(2) * inv_col2(M - 1) : inv_col2(2);
    const Scalar h = std::abs(det) * std::sqrt(inv_col2(0) * inv_col2(1)) * std::sqrt(tail) / std::sqrt(row_product);
    return std::isfinite(h) ? h : Scalar(0);
  }

  RatioEstimator<M, Scalar> ratio_;
  Matrix<Scalar, M, M> system_ = Matrix<Scalar, M, M>::Zero();
  Vector<Scalar, M> rhs_ = Vector<Scalar, M>::Zero();
  Vector<Scalar, M> instant_ = Vector<Scalar, M>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
  Scalar hadamard_ = Scalar(0);
  bool trusted_ = false;
};

}  // namespace algid
