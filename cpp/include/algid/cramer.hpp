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

/// Cramer's rule for a 4x4 system through the adjugate built from shared 2x2 minors
/// (about 110 flops): numerator = adj(S) b, det = Laplace expansion on rows (1,2)/(3,4).
/// @realtime no allocation, no throw
template <class Scalar>
inline CramerSolution<Scalar, 4> cramer(const Matrix<Scalar, 4, 4>& a, const Vector<Scalar, 4>& b) noexcept {
  const Scalar s0 = a(0, 0) * a(1, 1) - a(1, 0) * a(0, 1);
  const Scalar s1 = a(0, 0) * a(1, 2) - a(1, 0) * a(0, 2);
  const Scalar s2 = a(0, 0) * a(1, 3) - a(1, 0) * a(0, 3);
  const Scalar s3 = a(0, 1) * a(1, 2) - a(1, 1) * a(0, 2);
  const Scalar s4 = a(0, 1) * a(1, 3) - a(1, 1) * a(0, 3);
  const Scalar s5 = a(0, 2) * a(1, 3) - a(1, 2) * a(0, 3);
  const Scalar c5 = a(2, 2) * a(3, 3) - a(3, 2) * a(2, 3);
  const Scalar c4 = a(2, 1) * a(3, 3) - a(3, 1) * a(2, 3);
  const Scalar c3 = a(2, 1) * a(3, 2) - a(3, 1) * a(2, 2);
  const Scalar c2 = a(2, 0) * a(3, 3) - a(3, 0) * a(2, 3);
  const Scalar c1 = a(2, 0) * a(3, 2) - a(3, 0) * a(2, 2);
  const Scalar c0 = a(2, 0) * a(3, 1) - a(3, 0) * a(2, 1);
  CramerSolution<Scalar, 4> out;
  out.det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0;
  // numerator_j = sum_i adj(j, i) b_i, adj = transposed cofactors.
  out.numerator(0) = (a(1, 1) * c5 - a(1, 2) * c4 + a(1, 3) * c3) * b(0) +
                     (-a(0, 1) * c5 + a(0, 2) * c4 - a(0, 3) * c3) * b(1) +
                     (a(3, 1) * s5 - a(3, 2) * s4 + a(3, 3) * s3) * b(2) +
                     (-a(2, 1) * s5 + a(2, 2) * s4 - a(2, 3) * s3) * b(3);
  out.numerator(1) = (-a(1, 0) * c5 + a(1, 2) * c2 - a(1, 3) * c1) * b(0) +
                     (a(0, 0) * c5 - a(0, 2) * c2 + a(0, 3) * c1) * b(1) +
                     (-a(3, 0) * s5 + a(3, 2) * s2 - a(3, 3) * s1) * b(2) +
                     (a(2, 0) * s5 - a(2, 2) * s2 + a(2, 3) * s1) * b(3);
  out.numerator(2) = (a(1, 0) * c4 - a(1, 1) * c2 + a(1, 3) * c0) * b(0) +
                     (-a(0, 0) * c4 + a(0, 1) * c2 - a(0, 3) * c0) * b(1) +
                     (a(3, 0) * s4 - a(3, 1) * s2 + a(3, 3) * s0) * b(2) +
                     (-a(2, 0) * s4 + a(2, 1) * s2 - a(2, 3) * s0) * b(3);
  out.numerator(3) = (-a(1, 0) * c3 + a(1, 1) * c1 - a(1, 2) * c0) * b(0) +
                     (a(0, 0) * c3 - a(0, 1) * c1 + a(0, 2) * c0) * b(1) +
                     (-a(3, 0) * s3 + a(3, 1) * s1 - a(3, 2) * s0) * b(2) +
                     (a(2, 0) * s3 - a(2, 1) * s1 + a(2, 2) * s0) * b(3);
  return out;
}

/// Cramer's rule for a 3x3 system (column replacement, rule of Sarrus).
/// @realtime no allocation, no throw
template <class Scalar>
inline CramerSolution<Scalar, 3> cramer(const Matrix<Scalar, 3, 3>& a, const Vector<Scalar, 3>& b) noexcept {
  const auto det3 = [](const Vector<Scalar, 3>& x, const Vector<Scalar, 3>& y, const Vector<Scalar, 3>& z) {
    return x(0) * (y(1) * z(2) - y(2) * z(1)) - y(0) * (x(1) * z(2) - x(2) * z(1)) +
           z(0) * (x(1) * y(2) - x(2) * y(1));
  };
  const Vector<Scalar, 3> c0 = a.col(0), c1 = a.col(1), c2 = a.col(2);
  CramerSolution<Scalar, 3> out;
  out.det = det3(c0, c1, c2);
  out.numerator(0) = det3(b, c1, c2);
  out.numerator(1) = det3(c0, b, c2);
  out.numerator(2) = det3(c0, c1, b);
  return out;
}

}  // namespace algid
