// Cramer's rule (cramer_lanes4 / cramer_lanes3 / cramer_lanes<M>) on scalars against Eigen's LU
// and explicit column-replacement determinants; on lanes (systems side by side) equal, lane by
// lane, to the scalar form; the squared equilibrated Hadamard ratio (equilibrated_hadamard2)
// against its definition, on scalars and on lanes.
#include <algid/algebraic_system.hpp>
#include <algid/cramer.hpp>

#include <Eigen/Dense>

#include "check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

namespace {

template <int M>
using Mat = Eigen::Matrix<double, M, M>;
template <int M>
using Vec = Eigen::Matrix<double, M, 1>;

// Cramer on scalars: S column-major, as the estimator stores it.
template <int M>
void cramer_scalar(const Mat<M>& a, const Vec<M>& b, double& det, Vec<M>& numerator) {
  double S[M * M], s[M], num[M];
  for (int c = 0; c < M; ++c)
    for (int r = 0; r < M; ++r) S[c * M + r] = a(r, c);
  for (int r = 0; r < M; ++r) s[r] = b(r);
  algid::cramer_lanes<M>(S, s, det, num);
  for (int j = 0; j < M; ++j) numerator(j) = num[j];
}

// Doubly equilibrated Hadamard ratio from its definition: columns to unit norm, then rows, |det|.
template <int M>
double hadamard_definition(Mat<M> a) {
  for (int c = 0; c < M; ++c) a.col(c).normalize();
  for (int r = 0; r < M; ++r) a.row(r).normalize();
  return std::abs(a.determinant());
}

template <int M>
void against_lu(std::mt19937& gen) {
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  double worst = 0, worst_det = 0, worst_num = 0, worst_hadamard = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    Mat<M> a;
    Vec<M> b;
    for (int i = 0; i < M * M; ++i) a(i) = dist(gen);
    for (int i = 0; i < M; ++i) b(i) = dist(gen);
    double det;
    Vec<M> num;
    cramer_scalar<M>(a, b, det, num);
    const Vec<M> lu = a.partialPivLu().solve(b);
    worst = std::max(worst, ((num / det) - lu).norm() / lu.norm());
    worst_det = std::max(worst_det, std::abs(det - a.determinant()) / std::abs(a.determinant()));
    for (int j = 0; j < M; ++j) {
      Mat<M> r = a;
      r.col(j) = b;
      worst_num = std::max(worst_num, std::abs(num(j) - r.determinant()) / (1 + std::abs(r.determinant())));
    }
    double S[M * M], h2num, h2den;
    for (int c = 0; c < M; ++c)
      for (int r = 0; r < M; ++r) S[c * M + r] = a(r, c);
    algid::equilibrated_hadamard2<M>(S, det, h2num, h2den);
    worst_hadamard = std::max(worst_hadamard, std::abs(std::sqrt(h2num / h2den) - hadamard_definition<M>(a)));
  }
  std::printf(
      "%dx%d: worst relative difference to LU %.2e, det %.2e, numerators (to column-replaced determinants) "
      "%.2e, Hadamard ratio %.2e\n",
      M, M, worst, worst_det, worst_num, worst_hadamard);
  CHECK(worst < 1e-9);
  CHECK(worst_det < 1e-12);
  CHECK(worst_num < 1e-12);
  CHECK(worst_hadamard < 1e-13);
}

// W systems side by side in lanes give, lane by lane, what each gives on scalars: the same
// operations in the same order (bitwise in this build, which fuses no multiply-adds).
template <int M, int W>
void lanes_equal_scalars(std::mt19937& gen) {
  using L = algid::detail::Lanes<double, W>;
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  long differences = 0;
  for (int trial = 0; trial < 200; ++trial) {
    L S[M * M], s[M], det, num[M], h2num, h2den;
    for (auto& x : S)
      for (int k = 0; k < W; ++k) x(k) = dist(gen);
    for (auto& x : s)
      for (int k = 0; k < W; ++k) x(k) = dist(gen);
    if (trial == 0) S[M] = S[0];  // a singular system in lane 0...
    if (trial == 0) S[M + 1] = S[1];
    if (trial == 0 && M == 3) S[M + 2] = S[2];
    if (trial == 0 && M == 4) S[M + 2] = S[2], S[M + 3] = S[3];
    algid::cramer_lanes<M>(S, s, det, num);
    algid::equilibrated_hadamard2<M>(S, det, h2num, h2den);
    for (int k = 0; k < W; ++k) {
      double Sk[M * M], sk[M], dk, nk[M], hn, hd;
      for (int e = 0; e < M * M; ++e) Sk[e] = S[e](k);
      for (int e = 0; e < M; ++e) sk[e] = s[e](k);
      algid::cramer_lanes<M>(Sk, sk, dk, nk);
      algid::equilibrated_hadamard2<M>(Sk, dk, hn, hd);
      differences += dk != det(k) || hn != h2num(k) || hd != h2den(k);
      for (int j = 0; j < M; ++j) differences += nk[j] != num[j](k);
    }
    if (trial == 0) CHECK(det(0) == 0.0 && h2num(0) == 0.0);  // ...equal columns: det and ratio exactly 0
  }
  std::printf("%dx%d in %d lanes: %ld values differ from the scalar form\n", M, M, W, differences);
  CHECK(differences == 0);
}

}  // namespace

int main() {
  std::mt19937 gen(7);
  against_lu<4>(gen);
  against_lu<3>(gen);
  lanes_equal_scalars<4, 4>(gen);
  lanes_equal_scalars<4, 2>(gen);
  lanes_equal_scalars<3, 4>(gen);
  lanes_equal_scalars<3, 1>(gen);
  // A singular system gives det == 0 exactly in the structured case of equal columns.
  Mat<4> s = Mat<4>::Random();
  s.col(3) = s.col(2);
  double det;
  Vec<4> num;
  cramer_scalar<4>(s, Vec<4>::Ones(), det, num);
  CHECK(det == 0.0);
  // An orthogonal system has Hadamard ratio 1; a zero column makes num non-finite and det 0.
  const Mat<4> q = Eigen::HouseholderQR<Mat<4>>(Mat<4>::Random()).householderQ();
  double S[16], b[4] = {1, 2, 3, 4}, n4[4], h2num, h2den;
  for (int e = 0; e < 16; ++e) S[e] = q(e % 4, e / 4);
  algid::cramer_lanes4(S, b, det, n4);
  algid::equilibrated_hadamard2<4>(S, det, h2num, h2den);
  CHECK_NEAR(h2num / h2den, 1.0, 1e-12);
  for (int r = 0; r < 4; ++r) S[4 + r] = 0.0;
  algid::cramer_lanes4(S, b, det, n4);
  algid::equilibrated_hadamard2<4>(S, det, h2num, h2den);
  CHECK(det == 0.0 && !std::isfinite(h2num));
  return algid_test::finish("test_cramer");
}
