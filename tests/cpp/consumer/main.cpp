// Uses the installed headers through find_package(algid): a constant-parameter 1-DOF chain
// under a smooth force, closed form, estimated to 1e-6.
#include <algid/algid.hpp>

#include <cmath>
#include <cstdio>

int main() {
  algid::ChainEstimator<1>::Config cfg;
  cfg.dt = 1e-3;
  algid::ChainEstimator<1> est(cfg);
  const double m = 2.0, c = 3.0, k = 1200.0;  // k = k1 + k2
  for (int s = 0; s < 300; ++s) {
    const double t = s * cfg.dt;
    // x(t) = 1e-3 sin(40 t) + 5e-4 sin(97 t); u from eq. 1
    const double x = 1e-3 * std::sin(40 * t) + 5e-4 * std::sin(97 * t);
    const double v = 4e-2 * std::cos(40 * t) + 4.85e-2 * std::cos(97 * t);
    const double a = -1.6 * std::sin(40 * t) - 4.7045 * std::sin(97 * t);
    const double u = m * a + c * v + k * x;
    est.update(&a, &u);
  }
  const bool ok = std::abs(est.mass()(0) / m - 1) < 1e-6 && std::abs(est.damping()(0) / c - 1) < 1e-6 &&
                  std::abs(est.stiffness()(0) / k - 1) < 1e-6;
  std::printf("consumer: m = %.9g, c = %.9g, k1 + k2 = %.9g\nconsumer: %d passed, %d failed\n", est.mass()(0),
              est.damping()(0), est.stiffness()(0), ok ? 1 : 0, ok ? 0 : 1);
  return ok ? 0 : 1;
}
