#pragma once
// Closed-form chain trajectories for the estimator tests: every x_i(t) is a polynomial of
// degree 5, so y = x'' has degree 3 and the forces u = M x'' + C x' + K x degree 5; the
// eq. 4 integrands Delta^2 y and Delta^2 u have degree <= 7 and the 8-point quadrature
// integrates them exactly: the estimator must return the parameters to rounding.
#include <array>
#include <cmath>
#include <random>

namespace algid_test {

template <int N>
struct PolynomialChain {
  std::array<double, N> m{}, c{};
  std::array<double, N + 1> k{};
  std::array<std::array<double, 6>, N> coef{};  // x_i(t) = sum coef[i][d] t^d

  explicit PolynomialChain(unsigned seed, bool free_end = false) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5), s(-1.0, 1.0);
    for (int i = 0; i < N; ++i) {
      m[i] = 2.0 * u(gen);
      c[i] = 5.0 * u(gen);
      for (auto& a : coef[i]) a = 1e-3 * s(gen);
    }
    for (auto& kk : k) kk = 900.0 * u(gen);
    if (free_end) k[N] = 0.0;
  }
  double deriv(int i, int order, double t) const {
    double v = 0;
    for (int d = order; d < 6; ++d) {
      double f = 1;
      for (int q = 0; q < order; ++q) f *= d - q;
      v += coef[i][d] * f * std::pow(t, d - order);
    }
    return v;
  }
  double x(int i, double t) const { return (i < 0 || i >= N) ? 0.0 : deriv(i, 0, t); }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    return m[i] * deriv(i, 2, t) + c[i] * deriv(i, 1, t) + k[i] * (x(i, t) - x(i - 1, t)) +
           k[i + 1] * (x(i, t) - x(i + 1, t));
  }
};

// Multisine trajectories x_i(t) = sum_k A_ik sin(w_k t + phi_ik), forces from eq. 1 in closed
// form: smooth, persistently exciting, well-conditioned (not exact for the quadrature, which
// is O(h^8) on them).
template <int N>
struct SineChain {
  std::array<double, N> m{}, c{};
  std::array<double, N + 1> k{};
  static constexpr int kTones = 5;
  std::array<double, kTones> w{};
  std::array<std::array<double, kTones>, N> amp{}, phase{};

  explicit SineChain(unsigned seed) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5), ph(0.0, 6.283185307179586);
    for (int i = 0; i < N; ++i) {
      m[i] = 2.0 * u(gen);
      c[i] = 5.0 * u(gen);
      for (int q = 0; q < kTones; ++q) {
        amp[i][q] = 1e-3 * u(gen);
        phase[i][q] = ph(gen);
      }
    }
    for (auto& kk : k) kk = 900.0 * u(gen);
    for (int q = 0; q < kTones; ++q) w[q] = 2 * 3.141592653589793 * (2.0 + 5.3 * q) * u(gen);
  }
  double deriv(int i, int order, double t) const {
    if (i < 0 || i >= N) return 0.0;
    double v = 0;
    for (int q = 0; q < kTones; ++q) v += amp[i][q] * std::pow(w[q], order) * std::sin(w[q] * t + phase[i][q] + order * 1.5707963267948966);
    return v;
  }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    return m[i] * deriv(i, 2, t) + c[i] * deriv(i, 1, t) + k[i] * (deriv(i, 0, t) - deriv(i - 1, 0, t)) +
           k[i + 1] * (deriv(i, 0, t) - deriv(i + 1, 0, t));
  }
};

}  // namespace algid_test
