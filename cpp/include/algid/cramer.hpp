#pragma once
/// @file cramer.hpp
/// Cramer's rule for the 3x3 and 4x4 systems of eq. 5: the determinant Delta and the
/// numerators Delta_j (determinant with column j replaced by the right-hand side).
///
/// Many systems side by side: lane b of every entry belongs to system b (a DOF of a chain), and
/// an entry is a scalar (one system) or an Eigen array of lanes.

#include "algid/types.hpp"

namespace algid {

/// Cramer's rule for a 4x4 system by Laplace expansion along rows (1, 2) / (3, 4) of the
/// augmented matrix [S | b]: t_ij and u_ij are the 2x2 minors of rows 0, 1 and of rows 2, 3
/// over columns i, j (column 4 is b), and the determinant of columns (c0, c1, c2, c3) is the
/// sum over the three splits into pairs of +- (t(c0 c1) u(c2 c3) + t(c2 c3) u(c0 c1)); about
/// 115 flops. `S` holds the 16 entries column-major; writes the determinant and the four
/// numerators (column j replaced by b). @realtime no allocation, no throw
template <class L>
inline void cramer_lanes4(const L* S, const L* b, L& det, L* numerator) noexcept {
  const auto a = [&](int r, int c) -> const L& { return c == 4 ? b[r] : S[c * 4 + r]; };
  const auto t = [&](int i, int j) -> L { return a(0, i) * a(1, j) - a(0, j) * a(1, i); };
  const auto u = [&](int i, int j) -> L { return a(2, i) * a(3, j) - a(2, j) * a(3, i); };
  const L t01 = t(0, 1), t02 = t(0, 2), t03 = t(0, 3), t04 = t(0, 4), t12 = t(1, 2), t13 = t(1, 3), t14 = t(1, 4),
          t23 = t(2, 3), t24 = t(2, 4), t34 = t(3, 4);
  const L u01 = u(0, 1), u02 = u(0, 2), u03 = u(0, 3), u04 = u(0, 4), u12 = u(1, 2), u13 = u(1, 3), u14 = u(1, 4),
          u23 = u(2, 3), u24 = u(2, 4), u34 = u(3, 4);
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
