// Cramer's rule against Eigen's LU and against explicit column-replacement determinants.
#include <algid/cramer.hpp>

#include <Eigen/LU>

#include "check.hpp"

#include <random>

int main() {
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  double worst4 = 0, worst3 = 0, worst_det = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    Eigen::Matrix4d a;
    Eigen::Vector4d b;
    for (int i = 0; i < 16; ++i) a(i) = dist(gen);
    for (int i = 0; i < 4; ++i) b(i) = dist(gen);
    const auto sol = algid::cramer<double>(a, b);
    const Eigen::Vector4d lu = a.partialPivLu().solve(b);
    worst4 = std::max(worst4, ((sol.numerator / sol.det) - lu).norm() / lu.norm());
    worst_det = std::max(worst_det, std::abs(sol.det - a.determinant()) / std::abs(a.determinant()));
    for (int j = 0; j < 4; ++j) {
      Eigen::Matrix4d r = a;
      r.col(j) = b;
      CHECK_NEAR(sol.numerator(j), r.determinant(), 1e-12 * (1 + std::abs(r.determinant())));
    }
    const Eigen::Matrix3d a3 = a.topLeftCorner<3, 3>();
    const Eigen::Vector3d b3 = b.head<3>();
    const auto s3 = algid::cramer<double>(a3, b3);
    const Eigen::Vector3d lu3 = a3.partialPivLu().solve(b3);
    worst3 = std::max(worst3, ((s3.numerator / s3.det) - lu3).norm() / lu3.norm());
  }
  std::printf("worst relative difference to LU: 4x4 %.2e, 3x3 %.2e, det %.2e\n", worst4, worst3, worst_det);
  CHECK(worst4 < 1e-9);
  CHECK(worst3 < 1e-9);
  CHECK(worst_det < 1e-12);
  // A singular system gives det == 0 exactly in the structured case of equal columns.
  Eigen::Matrix4d s = Eigen::Matrix4d::Random();
  s.col(3) = s.col(2);
  CHECK_NEAR(algid::cramer<double>(s, Eigen::Vector4d::Ones()).det, 0.0, 1e-15);
  return algid_test::finish("test_cramer");
}
