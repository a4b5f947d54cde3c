#pragma once
/// @file algebraic_system.hpp
/// The time-scaled system of eq. 5 of a DOF, built from the integrator chains of its own
/// acceleration, its neighbours' accelerations and its force; the validity rule that decides
/// whether its Cramer solution enters eq. 7. Every function works on one system or, lane by
/// lane, on W systems side by side (an Eigen array of lanes).
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
/// so a signal's rows are computed once (`signal_row()`) and shared by the DOFs it enters.
///
/// Validity rule: a sample is *trusted* when (i) at least `min_samples` samples have been
/// consumed since t0, (ii) det S is finite and non-zero, and (iii) the Hadamard ratio of S
/// after scaling every column and then every row to unit norm, |det| / prod(norms), is at
/// least `min_hadamard` (1 for orthogonal columns, 0 for a singular system: it catches the
/// structurally singular cases, e.g. a constant force since t0, for which B = 0). Only trusted
/// samples enter eq. 7, and the eq. 7 estimate is valid once one has.

#include "algid/detail/lanes.hpp"
#include "algid/types.hpp"

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

/// Row q, column s - q of a signal, R(q, s) = J_s - kRowA[q] J_(s+1) + kRowB[q] J_(s+2) (the
/// recurrence in the file comment), lane by lane from its time-scaled integrals J.
/// @realtime no allocation, no throw
template <class Scalar, int W>
inline detail::Lanes<Scalar, W> signal_row(const detail::Lanes<Scalar, W>* J, int q, int s) noexcept {
  using L = detail::Lanes<Scalar, W>;
  using Ops = detail::LaneOps<Scalar, W>;
  return Ops::madd(L::Constant(static_cast<Scalar>(kRowB[q])), J[s + 2],
                   Ops::madd(L::Constant(static_cast<Scalar>(-kRowA[q])), J[s + 1], J[s]));
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

/// The validity rule and eq. 7's input for systems side by side in lanes (one system per lane:
/// a DOF, or an instant): from the determinants, the Cramer numerators scaled to the physical
/// parameters (`scaled`, M of them), the squared Hadamard ratio h2num / h2den (h2num is set to
/// 0 where it is not finite: a zero column) and the samples consumed since t0 at each lane's
/// instant, the weight of eq. 7 (|det| where trusted, 0 elsewhere: a zero or non-finite det, a
/// low Hadamard ratio, too few samples) and the weighted numerators (sgn(det) scaled where
/// trusted, 0 elsewhere).
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

}  // namespace algid
