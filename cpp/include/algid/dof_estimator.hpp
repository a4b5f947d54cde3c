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
/// Entries. Row q (q = 0..3) of eq. 5 is the q-fold integral (eq. 6) of eq. 4, whose
/// operators on a signal f are Delta^2 f - 4 I(Delta f) + 2 I^2 f (mass column on y_i, and
/// the right-hand side on u_i), I(Delta^2 f) - 2 I^2(Delta f) (damping) and I^2(Delta^2 f)
/// (springs, on y_i minus a neighbour's). With the identity of integrator_chain.hpp and the
/// time-scaled integrals J_k = I^k f / tau^k all three are one three-term recurrence,
///
///   R(q, s) = J_s - 2 (q+2) J_(s+1) + (q+2)(q+3) J_(s+2),
///   S(q, 0) = R_yi(q, q),  S(q, 1) = R_yi(q, q+1),
///   S(q, 2) = R_yi(q, q+2) - R_y(i-1)(q, q+2),  S(q, 3) = R_yi(q, q+2) - R_y(i+1)(q, q+2),
///   s(q) = R_ui(q, q),
///
/// so a signal's rows are computed once (`signal_rows()`) and shared by the DOFs it enters.
///
/// Validity rule: a sample is *trusted* when (i) at least `min_samples` samples have been
/// consumed since t0, (ii) det S is finite and non-zero, and (iii) the Hadamard ratio of S
/// after scaling every column and then every row to unit norm, |det| / prod(norms), is at
/// least `min_hadamard` (1 for orthogonal columns, 0 for a singular system: it catches the
/// structurally singular cases, e.g. a constant force since t0, for which B = 0). Only trusted
/// samples enter eq. 7, and the eq. 7 estimate is valid once one has.

#include "algid/cramer.hpp"
#include "algid/detail/lanes.hpp"
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

/// Time-scaled integrals a signal's rows need: J_0 .. J_7 of an acceleration (the spring
/// column reaches R(3, 5), i.e. J_7), J_0 .. J_5 of a force.
inline constexpr int kAccelOrders = 7;
inline constexpr int kForceOrders = 5;

/// Coefficients of the row recurrence R(q, s) = J_s - kRowA[q] J_(s+1) + kRowB[q] J_(s+2):
/// 2 (q + 2) and (q + 2)(q + 3).
inline constexpr int kRowA[4] = {4, 6, 8, 10};
inline constexpr int kRowB[4] = {6, 12, 20, 30};

/// The rows of one signal at one instant: column c holds R(q, q + c), q = 0 .. Rows - 1 (the
/// recurrence in the file comment), for c < Cols; rows q >= Rows are left as they are.
/// @tparam Cols 3 for an acceleration (mass, damping, spring columns), 1 for a force.
/// @tparam Rows 4, or 3 where only 3x3 systems are solved (a chain of one DOF).
/// @param J time-scaled integrals J_0 .. J_(Cols + Rows).
/// @realtime no allocation, no throw
template <int Cols, int Rows = 4, class Scalar>
inline void signal_rows(const Scalar* J, Matrix<Scalar, 4, Cols>& rows) noexcept {
  static_assert(Rows == 3 || Rows == 4, "eq. 5 systems are 3x3 or 4x4");
  using Column = Eigen::Array<Scalar, Rows, 1>;
  const Column a = Eigen::Array<int, 4, 1>(kRowA[0], kRowA[1], kRowA[2], kRowA[3]).template head<Rows>().template cast<Scalar>();
  const Column b = Eigen::Array<int, 4, 1>(kRowB[0], kRowB[1], kRowB[2], kRowB[3]).template head<Rows>().template cast<Scalar>();
  const Eigen::Map<const Eigen::Array<Scalar, Cols + Rows + 1, 1>> j(J);
  for (int c = 0; c < Cols; ++c) {
    rows.col(c).template head<Rows>().array() = j.template segment<Rows>(c) - a * j.template segment<Rows>(c + 1) +
                                                b * j.template segment<Rows>(c + 2);
  }
}

/// What every DOF of a chain shares at one instant (computed once per sample).
template <class Scalar>
struct Instant {
  Scalar inv_tau = Scalar(0);  ///< 1 / tau, tau = t - t0 of the interval end [1/s]
  Scalar h = Scalar(0);        ///< sample period [s]
  Scalar decay4 = Scalar(0);   ///< RatioEstimator<4>::decay(previous tau, tau)
  Scalar decay3 = Scalar(0);   ///< RatioEstimator<3>::decay(previous tau, tau)
  long samples = 0;            ///< samples consumed since t0
};

/// The time-scaled system of eq. 5 of one DOF from the rows of its signals (see the file
/// comment): `self`, `left`, `right` are acceleration rows (4 x 3, column-major; `left` /
/// `right` nullptr at a wall), `force` the force rows (4 x 1). Writes S (M x M, column-major)
/// and s (M). Entries are scalars or Eigen arrays of lanes (one system per lane).
/// @realtime no allocation, no throw
template <int M, class L>
inline void assemble_system(const L* left, const L* self, const L* right, const L* force, L* S, L* s) noexcept {
  for (int q = 0; q < M; ++q) {
    S[0 * M + q] = self[0 * 4 + q];
    S[1 * M + q] = self[1 * 4 + q];
    S[2 * M + q] = left ? L(self[2 * 4 + q] - left[2 * 4 + q]) : self[2 * 4 + q];
    if constexpr (M == 4) S[3 * M + q] = right ? L(self[2 * 4 + q] - right[2 * 4 + q]) : self[2 * 4 + q];
    s[q] = force[q];
  }
}

/// Squared doubly equilibrated Hadamard ratio of S (M x M, column-major) as num / den:
/// det^2 / prod(squared column norms) over prod(squared norms of the rows of the
/// column-normalised matrix), with the determinant paired with two inverse column norms at a
/// time so that nothing leaves the range of single precision (normalised rows have squared
/// norms <= M). No square root, one reciprocal per column. A zero column makes num non-finite
/// (the caller reads that as 0) and det is then 0, so the system is never trusted. Entries are
/// scalars or Eigen arrays of lanes; every sum is written out so both give the same bits.
/// @realtime no allocation, no throw
template <int M, class L>
inline void equilibrated_hadamard2(const L* S, const L& det, L& num, L& den) noexcept {
  L sq[M * M];
  for (int e = 0; e < M * M; ++e) sq[e] = S[e] * S[e];
  L inv_col2[M];
  for (int c = 0; c < M; ++c) {
    L col2 = sq[c * M];
    for (int r = 1; r < M; ++r) col2 = col2 + sq[c * M + r];
    inv_col2[c] = detail::reciprocal(col2);
  }
  L row2[M];
  for (int r = 0; r < M; ++r) {
    row2[r] = sq[r] * inv_col2[0];
    for (int c = 1; c < M; ++c) row2[r] = row2[r] + sq[c * M + r] * inv_col2[c];
  }
  den = row2[0];
  for (int r = 1; r < M; ++r) den = den * row2[r];
  const L tail = M == 4 ? L(inv_col2[2] * inv_col2[M - 1]) : inv_col2[2];
  num = (det * inv_col2[0] * inv_col2[1]) * (det * tail);
}

/// equilibrated_hadamard2() of one system, vectorised across columns and rows: every entry
/// sees the operations of the lane form, in the same order (same bits), in fewer instructions.
/// @realtime no allocation, no throw
template <int M, class Scalar>
inline void equilibrated_hadamard2(const Matrix<Scalar, M, M>& S, Scalar det, Scalar& num, Scalar& den) noexcept {
  using Row = Eigen::Array<Scalar, 1, M>;
  using Column = Eigen::Array<Scalar, M, 1>;
  const Eigen::Array<Scalar, M, M> sq = S.array().square();
  Row col2 = sq.row(0);
  for (int r = 1; r < M; ++r) col2 = col2 + sq.row(r);
  const Row inv_col2 = col2.inverse();
  Column row2 = sq.col(0) * inv_col2(0);
  for (int c = 1; c < M; ++c) row2 = row2 + sq.col(c) * inv_col2(c);
  den = row2(0);
  for (int r = 1; r < M; ++r) den = den * row2(r);
  const Scalar tail = M == 4 ? inv_col2(2) * inv_col2(M - 1) : inv_col2(2);
  num = (det * inv_col2(0) * inv_col2(1)) * (det * tail);
}

/// The validity rule and eq. 7's input for systems side by side in lanes (one system per lane:
/// a DOF, or an instant): from the determinants, the Cramer numerators scaled to the physical
/// parameters (`scaled`, M of them), the squared Hadamard ratio h2num / h2den (h2num is set to
/// 0 where it is not finite: a zero column) and the samples consumed since t0 at each lane's
/// instant, the weight of eq. 7 (|det| where trusted, 0 elsewhere: a zero or non-finite det, a
/// low Hadamard ratio, too few samples) and the weighted numerators (sgn(det) scaled where
/// trusted, 0 elsewhere). The arithmetic of DofEstimator::commit(), lane by lane.
/// @realtime no allocation, no throw
template <int M, class Scalar, int W>
inline void weigh_lanes(const detail::Lanes<Scalar, W>& det, const detail::Lanes<Scalar, W>* scaled,
                        detail::Lanes<Scalar, W>& h2num, const detail::Lanes<Scalar, W>& h2den,
                        const detail::Lanes<Scalar, W>& samples, const ValidityRule<Scalar>& rule,
                        detail::Lanes<Scalar, W>& weight, detail::Lanes<Scalar, W>* weighted) noexcept {
  using Ops = detail::LaneOps<Scalar, W>;
  using L = detail::Lanes<Scalar, W>;
  const L zero = L::Zero(), one = L::Ones(), inf = L::Constant(std::numeric_limits<Scalar>::infinity());
  h2num = Ops::if_less(h2num.abs(), inf, h2num, zero);
  weight = det.abs();
  weight = Ops::if_less(weight, inf, weight, zero);
  weight = Ops::if_less_equal(rule.min_hadamard * rule.min_hadamard * h2den, h2num, weight, zero);
  weight = Ops::if_less_equal(L::Constant(static_cast<Scalar>(rule.min_samples)), samples, weight, zero);
  const L sign = Ops::if_less(zero, det, one, -one);
  for (int j = 0; j < M; ++j) weighted[j] = Ops::if_less(zero, weight, sign * scaled[j], zero);
}

/// Eq. 7 estimates lane by lane from the scaled double integrals: num[j] / den where den > 0
/// (a trusted sample has entered), NaN elsewhere. @realtime no allocation, no throw
template <int M, class Scalar, int W>
inline void estimates_lanes(const detail::Lanes<Scalar, W>& den, const detail::Lanes<Scalar, W>* num,
                            detail::Lanes<Scalar, W>* estimate) noexcept {
  using L = detail::Lanes<Scalar, W>;
  const L inv = L::Ones() / den;
  for (int j = 0; j < M; ++j)
    estimate[j] = detail::LaneOps<Scalar, W>::if_less(L::Zero(), den, num[j] * inv,
                                                      L::Constant(std::numeric_limits<Scalar>::quiet_NaN()));
}

/// Estimator of theta_i = [m_i, c_i, k_i, k_{i+1}] for one DOF.
/// @tparam M 4 (the paper) or 3 (k_{i+1} known to be zero, or n = 1 where only k_1 + k_2 is
/// identifiable: then theta = [m, c, k_1 + k_2]).
template <int M, class Scalar = double>
class DofEstimator {
  static_assert(M == 3 || M == 4, "eq. 5 systems are 3x3 or 4x4");

 public:
  /// Rows of an acceleration signal (see signal_rows()).
  using AccelRows = Matrix<Scalar, 4, 3>;
  /// Rows of a force signal.
  using ForceRows = Matrix<Scalar, 4, 1>;
  /// What eq. 7 is fed per sample, [weight, weighted_0 .. weighted_(M-1), 0 ...] (see
  /// RatioEstimator::add()).
  using Packed = typename RatioEstimator<M, Scalar>::Packed;

  /// Start a new window. @realtime no allocation, no throw
  void reset() noexcept {
    ratio_.reset();
    numerator_.setZero();
    det_ = Scalar(0);
    hadamard2_num_ = Scalar(0);
    hadamard2_den_ = Scalar(1);
    trusted_ = false;
  }

  /// Advance to `now`. `left` and `right` are the neighbours' acceleration rows (nullptr at a
  /// wall), `self` this DOF's, `force` its force rows. @realtime no allocation, no throw
  void update(const AccelRows* left, const AccelRows& self, const AccelRows* right, const ForceRows& force,
              const Instant<Scalar>& now, const ValidityRule<Scalar>& rule) noexcept {
    // assemble_system(), column by column.
    system_.col(0) = self.col(0).template head<M>();
    system_.col(1) = self.col(1).template head<M>();
    if (left) {
      system_.col(2) = (self.col(2) - left->col(2)).template head<M>();
    } else {
      system_.col(2) = self.col(2).template head<M>();
    }
    if constexpr (M == 4) {
      if (right) {
        system_.col(3) = self.col(2) - right->col(2);
      } else {
        system_.col(3) = self.col(2);
      }
    }
    rhs_ = force.col(0).template head<M>();
    const CramerSolution<Scalar, M> sol = cramer(system_, rhs_);
    Scalar h2num, h2den;
    equilibrated_hadamard2(system_, sol.det, h2num, h2den);
    commit(sol.det, sol.numerator.data(), h2num, h2den, now, rule);
  }

  /// The second half of update() for a system solved elsewhere (the block path of
  /// ChainEstimator::run(), which solves many instants side by side): `det` and `numerator`
  /// from cramer() of the time-scaled system, `h2num` / `h2den` from equilibrated_hadamard2().
  /// Applies the validity rule and feeds eq. 7. @realtime no allocation, no throw
  void commit(Scalar det, const Scalar* numerator, Scalar h2num, Scalar h2den, const Instant<Scalar>& now,
              const ValidityRule<Scalar>& rule) noexcept {
    const Scalar inv2 = now.inv_tau * now.inv_tau;
    // Built in registers: filling a vector entry by entry and then reading it as one SIMD
    // vector would stall on the store-to-load forwarding.
    Vector<Scalar, M> scaled;
    if constexpr (M == 4) {
      scaled = Vector<Scalar, 4>(numerator[0], numerator[1] * now.inv_tau, numerator[2] * inv2, numerator[3] * inv2);
    } else {
      scaled = Vector<Scalar, 3>(numerator[0], numerator[1] * now.inv_tau, numerator[2] * inv2);
    }
    h2num = std::isfinite(h2num) ? h2num : Scalar(0);
    const bool solvable = std::isfinite(det) && det != Scalar(0);
    const bool trusted = solvable && now.samples >= rule.min_samples &&
                         h2num >= rule.min_hadamard * rule.min_hadamard * h2den;
    Packed x = Packed::Zero();  // in whole registers of 4
    if (trusted) {
      const Scalar sign = det > Scalar(0) ? Scalar(1) : Scalar(-1);
      x.template head<4>() = Vector<Scalar, 4>(std::abs(det), sign * scaled(0), sign * scaled(1), sign * scaled(2));
      if constexpr (M == 4) x.template segment<4>(4) = Vector<Scalar, 4>(sign * scaled(3), Scalar(0), Scalar(0), Scalar(0));
    }
    commit_weighed(det, scaled, h2num, h2den, x, M == 4 ? now.decay4 : now.decay3, now.h);
  }

  /// commit() for a sample weighed elsewhere with the same arithmetic (weigh_lanes(): the block
  /// path of ChainEstimator::run() weighs many instants side by side): `scaled` the M
  /// time-scaled Cramer numerators (a vector), `h2num` with 0 where it was not finite, `x` what
  /// eq. 7 is fed (x(0) > 0 exactly when the sample is trusted), `decay` this system size's
  /// decay factor, `h` the sample period [s]. @realtime no allocation, no throw
  template <class Scaled>
  void commit_weighed(Scalar det, const Eigen::MatrixBase<Scaled>& scaled, Scalar h2num, Scalar h2den, const Packed& x,
                      Scalar decay, Scalar h) noexcept {
    det_ = det;
    numerator_ = scaled;
    hadamard2_num_ = h2num;
    hadamard2_den_ = h2den;
    trusted_ = x(0) > Scalar(0);
    ratio_.add(decay, h, x);
  }

  /// Eq. 7 alone for a sample weighed elsewhere (`x`, `decay`, `h` as commit_weighed()), when
  /// nothing reads this sample's instantaneous solution, Hadamard ratio or trust flag: they
  /// keep the values of the last commit. @realtime no allocation, no throw
  void accumulate(const Packed& x, Scalar decay, Scalar h) noexcept { ratio_.add(decay, h, x); }

  /// Eq. 7's scaled double integrals (RatioEstimator::integrals()).
  const Packed& integrals() const noexcept { return ratio_.integrals(); }

  /// Set the system reported by system() / rhs() (the block path solves it elsewhere).
  /// @realtime no allocation, no throw
  void set_system(const Scalar* S, const Scalar* b) noexcept {
    system_ = Eigen::Map<const Matrix<Scalar, M, M>>(S);
    rhs_ = Eigen::Map<const Vector<Scalar, M>>(b);
  }

  /// Instantaneous Cramer solution of eq. 5 at the last update (NaN if singular).
  Vector<Scalar, M> instant() const noexcept {
    if (!(std::isfinite(det_) && det_ != Scalar(0)))
      return Vector<Scalar, M>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    return numerator_ * (Scalar(1) / det_);
  }
  /// True if the last sample was trusted (see the validity rule).
  bool instant_valid() const noexcept { return trusted_; }
  /// Eq. 7 estimate of parameter j; meaningful when valid().
  Scalar estimate(int j) const noexcept { return ratio_.estimate(j); }
  /// All eq. 7 estimates; meaningful when valid().
  Vector<Scalar, M> estimates() const noexcept { return ratio_.estimates(); }
  /// All eq. 7 estimates in slots 1 .. M of a packed vector (RatioEstimator::packed_estimates()).
  Packed packed_estimates() const noexcept { return ratio_.packed_estimates(); }
  /// True once eq. 7 has integrated a trusted sample.
  bool valid() const noexcept { return ratio_.valid(); }
  /// Doubly equilibrated Hadamard ratio of the last system, in [0, 1].
  Scalar hadamard() const noexcept {
    const Scalar h2 = hadamard2_num_ / hadamard2_den_;
    return std::isfinite(h2) && h2 > Scalar(0) ? std::sqrt(h2) : Scalar(0);
  }
  /// The last time-scaled system S and right-hand side s.
  const Matrix<Scalar, M, M>& system() const noexcept { return system_; }
  const Vector<Scalar, M>& rhs() const noexcept { return rhs_; }
  /// Eq. 7's accumulated weight (scaled), for fusion.
  Scalar weight() const noexcept { return ratio_.denominator(); }

 private:
  RatioEstimator<M, Scalar> ratio_;
  Matrix<Scalar, M, M> system_ = Matrix<Scalar, M, M>::Zero();
  Vector<Scalar, M> rhs_ = Vector<Scalar, M>::Zero();
  Vector<Scalar, M> numerator_ = Vector<Scalar, M>::Zero();  // Cramer numerators, time-unscaled
  Scalar det_ = Scalar(0);
  Scalar hadamard2_num_ = Scalar(0);
  Scalar hadamard2_den_ = Scalar(1);
  bool trusted_ = false;
};

}  // namespace algid
