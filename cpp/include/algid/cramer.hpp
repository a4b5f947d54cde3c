#pragma once
/// @file cramer.hpp
/// Cramer's rule for the 3x3 and 4x4 systems of eq. 5: the determinant Delta and the
/// numerators Delta_j (determinant with column j replaced by the right-hand side).

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

/// Cramer's rule for a 3x3 system: expansion along row 1 with the 2x2 minors of rows 2, 3 of
/// the augmented matrix [S | b]. @realtime no allocation, no throw
template <class Scalar>
inline CramerSolution<Scalar, 3> cramer(const Matrix<Scalar, 3, 3>& a, const Vector<Scalar, 3>& b) noexcept {
  // m_ij: minor of rows 1, 2 and columns i < j of [S | b] (column 3 = b).
  const Scalar m01 = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
  const Scalar m02 = a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0);
  const Scalar m03 = a(1, 0) * b(2) - b(1) * a(2, 0);
  const Scalar m12 = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
  const Scalar m13 = a(1, 1) * b(2) - b(1) * a(2, 1);
  const Scalar m23 = a(1, 2) * b(2) - b(1) * a(2, 2);
  CramerSolution<Scalar, 3> out;
  out.det = a(0, 0) * m12 - a(0, 1) * m02 + a(0, 2) * m01;
  out.numerator(0) = b(0) * m12 + a(0, 1) * m23 - a(0, 2) * m13;   // columns (b, 1, 2)
  out.numerator(1) = -a(0, 0) * m23 - b(0) * m02 + a(0, 2) * m03;  // columns (0, b, 2)
  out.numerator(2) = a(0, 0) * m13 - a(0, 1) * m03 + b(0) * m01;   // columns (0, 1, b)
  return out;
}

}  // namespace algid
