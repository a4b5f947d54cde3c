#pragma once
/// @file cramer.hpp
/// Cramer's rule for the 3x3 and 4x4 systems of eq. 5: the determinant Delta and the
/// numerators Delta_j (determinant with column j replaced by the right-hand side).
///
/// Two forms of each: one system (`cramer()`, for the per-sample update of one DOF) and many
/// systems side by side (`cramer_lanes()`, for the DOF of a chain or a block of instants: lane b
/// of every entry belongs to system b, and an entry is a scalar or an Eigen array of lanes). The
/// lane form performs, lane by lane, the same operations in the same order as the single-system
/// form, so its results are bitwise identical (no FMA contraction: see CMakeLists.txt).

#include "algid/types.hpp"

namespace algid {

/// Determinant and Cramer numerators of one system `S x = b`; x_j = numerator_j / det.
template <class Scalar, int M>
struct CramerSolution {
  Scalar det = Scalar(0);                               ///< Delta
  Vector<Scalar, M> numerator = Vector<Scalar, M>::Zero();  ///< Delta_1 .. Delta_M
};

/// Cramer's rule for a 4x4 system by Laplace expansion along rows (1, 2) / (3, 4) of the
/// augmented matrix [S | b]. The 2x2 minors of rows 0, 1 and of rows 2, 3 over the same pair of
/// columns are computed side by side, as one two-lane packet m_ij = (t_ij, u_ij), which is how
/// the ten pairs of minors and the five determinants (Delta and the four numerators, column j
/// replaced by b) vectorise; about 115 flops, half of them in packets.
/// @realtime no allocation, no throw
template <class Scalar>
inline CramerSolution<Scalar, 4> cramer(const Matrix<Scalar, 4, 4>& a, const Vector<Scalar, 4>& b) noexcept {
  using Pair = Eigen::Array<Scalar, 2, 1>;
  // Column c of [S | b] as the packets (row 0, row 2) and (row 1, row 3); c = 4 is b.
  Pair top[5], bottom[5];
  for (int c = 0; c < 4; ++c) {
    top[c] = Pair(a(0, c), a(2, c));
    bottom[c] = Pair(a(1, c), a(3, c));
  }
  top[4] = Pair(b(0), b(2));
  bottom[4] = Pair(b(1), b(3));
  // m_ij = (minor of rows 0, 1, minor of rows 2, 3) over columns i, j.
  const auto minor = [&](int i, int j) -> Pair { return top[i] * bottom[j] - top[j] * bottom[i]; };
  const Pair m01 = minor(0, 1), m02 = minor(0, 2), m03 = minor(0, 3), m04 = minor(0, 4);
  const Pair m12 = minor(1, 2), m13 = minor(1, 3), m14 = minor(1, 4);
  const Pair m23 = minor(2, 3), m24 = minor(2, 4), m34 = minor(3, 4);
  // The determinant of columns (c0, c1, c2, c3) is the sum over the three splits into pairs of
  // +- (t(c0 c1) u(c2 c3) + t(c2 c3) u(c0 c1)): one packet product with the lanes swapped.
  const auto split = [](const Pair& x, const Pair& y) -> Pair { return x * y.reverse(); };
  CramerSolution<Scalar, 4> out;
  out.det = (split(m01, m23) - split(m02, m13) + split(m03, m12)).sum();
  out.numerator(0) = (split(m24, m13) - split(m14, m23) - split(m34, m12)).sum();  // (b, 1, 2, 3)
  out.numerator(1) = (split(m04, m23) + split(m02, m34) - split(m03, m24)).sum();  // (0, b, 2, 3)
  out.numerator(2) = (split(m03, m14) - split(m01, m34) - split(m04, m13)).sum();  // (0, 1, b, 3)
  out.numerator(3) = (split(m01, m24) - split(m02, m14) + split(m04, m12)).sum();  // (0, 1, 2, b)
  return out;
}

/// cramer() for a 4x4 system whose entries are lanes (`L`: a scalar or an Eigen array, one
/// system per lane). `S` holds the 16 entries column-major, `b` the right-hand side; writes the
/// determinant and the four numerators. Per lane the operations of the packet form above:
/// t_ij / u_ij are its lane 0 / lane 1 (the minors of rows 0, 1 and of rows 2, 3) and every
/// determinant is (its lane-0 sum) + (its lane-1 sum). @realtime no allocation, no throw
template <class L>
inline void cramer_lanes4(const L* S, const L* b, L& det, L* numerator) noexcept {
  const auto a = [&](int r, int c) -> const L& { return c == 4 ? b[r] : S[c * 4 + r]; };
  const auto t = [&](int i, int j) -> L { return a(0, i) * a(1, j) - a(0, j) * a(1, i); };
  const auto u = [&](int i, int j) -> L { return a(2, i) * a(3, j) - a(2, j) * a(3, i); };
  const L t01 = t(0, 1), t02 = t(0, 2), t03 = t(0, 3), t04 = t(0, 4), t12 = t(1, 2), t13 = t(1, 3),
          t14 = t(1, 4), t23 = t(2, 3), t24 = t(2, 4), t34 = t(3, 4);
  const L u01 = u(0, 1), u02 = u(0, 2), u03 = u(0, 3), u04 = u(0, 4), u12 = u(1, 2), u13 = u(1, 3),
          u14 = u(1, 4), u23 = u(2, 3), u24 = u(2, 4), u34 = u(3, 4);
  det = ((t01 * u23 - t02 * u13) + t03 * u12) + ((u01 * t23 - u02 * t13) + u03 * t12);
  numerator[0] = ((t24 * u13 - t14 * u23) - t34 * u12) + ((u24 * t13 - u14 * t23) - u34 * t12);
  numerator[1] = ((t04 * u23 + t02 * u34) - t03 * u24) + ((u04 * t23 + u02 * t34) - u03 * t24);
  numerator[2] = ((t03 * u14 - t01 * u34) - t04 * u13) + ((u03 * t14 - u01 * t34) - u04 * t13);
  numerator[3] = ((t01 * u24 - t02 * u14) + t04 * u12) + ((u01 * t24 - u02 * t14) + u04 * t12);
}

/// Cramer's rule for a 3x3 system whose entries are lanes (or scalars): expansion along row 1
/// with the 2x2 minors of rows 2, 3 of the augmented matrix [S | b]. @realtime no allocation,
/// no throw
template <class L>
inline void cramer_lanes3(const L* S, const L* b, L& det, L* numerator) noexcept {
  const auto a = [&](int r, int c) -> const L& { return S[c * 3 + r]; };
  const L m01 = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
  const L m02 = a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0);
  const L m03 = a(1, 0) * b[2] - b[1] * a(2, 0);
  const L m12 = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
  const L m13 = a(1, 1) * b[2] - b[1] * a(2, 1);
  const L m23 = a(1, 2) * b[2] - b[1] * a(2, 2);
  det = a(0, 0) * m12 - a(0, 1) * m02 + a(0, 2) * m01;
  numerator[0] = b[0] * m12 + a(0, 1) * m23 - a(0, 2) * m13;
  numerator[1] = -a(0, 0) * m23 - b[0] * m02 + a(0, 2) * m03;
  numerator[2] = a(0, 0) * m13 - a(0, 1) * m03 + b[0] * m01;
}

/// Cramer's rule for one 3x3 system (cramer_lanes3() on scalars). @realtime no allocation, no throw
template <class Scalar>
inline CramerSolution<Scalar, 3> cramer(const Matrix<Scalar, 3, 3>& a, const Vector<Scalar, 3>& b) noexcept {
  CramerSolution<Scalar, 3> out;
  cramer_lanes3(a.data(), b.data(), out.det, out.numerator.data());
  return out;
}

/// cramer_lanes4 / cramer_lanes3 by size. @realtime no allocation, no throw
template <int M, class L>
inline void cramer_lanes(const L* S, const L* b, L& det, L* numerator) noexcept {
  static_assert(M == 3 || M == 4, "eq. 5 systems are 3x3 or 4x4");
  if constexpr (M == 4) {
    cramer_lanes4(S, b, det, numerator);
  } else {
    cramer_lanes3(S, b, det, numerator);
  }
}

}  // namespace algid
