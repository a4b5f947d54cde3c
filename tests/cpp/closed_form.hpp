#pragma once
// Closed-form chain trajectories for the estimator tests, for a number of DOF n given at run
// time (PolynomialChainN, SineChainN: what ChainEstimator<Dynamic> is fed) or as a template
// argument (PolynomialChain<N>, SineChain<N>: the same chains, the same draws for a seed).
//  - PolynomialChainN: every x_i(t) is a polynomial of degree 5, so y = x'' has degree 3 and the
//    forces u = M x'' + C x' + K x degree 5; the eq. 4 integrands Delta^2 y and Delta^2 u have
//    degree <= 7 and the 8-point quadrature integrates them exactly: the estimator must return
//    the parameters to rounding.
//  - SineChainN: multisine trajectories x_i(t) = sum_k A_ik sin(w_k t + phi_ik), forces from
//    eq. 1 in closed form: smooth, persistently exciting, well-conditioned (not exact for the
//    quadrature, which is O(h^8) on them).
#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace algid_test {

struct PolynomialChainN {
  int n;
  std::vector<double> m, c, k;               // n, n, n + 1
  std::vector<std::array<double, 6>> coef;   // x_i(t) = sum coef[i][d] t^d

  PolynomialChainN(int dofs, unsigned seed, bool free_end = false)
      : n(dofs),
        m(static_cast<std::size_t>(dofs)),
        c(m),
        k(static_cast<std::size_t>(dofs) + 1),
        coef(static_cast<std::size_t>(dofs)) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5), s(-1.0, 1.0);
    for (std::size_t i = 0; i < m.size(); ++i) {
      m[i] = 2.0 * u(gen);
      c[i] = 5.0 * u(gen);
      for (auto& a : coef[i]) a = 1e-3 * s(gen);
    }
    for (auto& kk : k) kk = 900.0 * u(gen);
    if (free_end) k.back() = 0.0;
  }
  double deriv(int i, int order, double t) const {
    double v = 0;
    for (int d = order; d < 6; ++d) {
      double f = 1;
      for (int q = 0; q < order; ++q) f *= d - q;
      v += coef[static_cast<std::size_t>(i)][static_cast<std::size_t>(d)] * f * std::pow(t, d - order);
    }
    return v;
  }
  double x(int i, double t) const { return (i < 0 || i >= n) ? 0.0 : deriv(i, 0, t); }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    const std::size_t a = static_cast<std::size_t>(i);
    return m[a] * deriv(i, 2, t) + c[a] * deriv(i, 1, t) + k[a] * (x(i, t) - x(i - 1, t)) +
           k[a + 1] * (x(i, t) - x(i + 1, t));
  }
};

struct SineChainN {
  static constexpr int kTones = 5;
  int n;
  std::vector<double> m, c, k;  // n, n, n + 1
  std::array<double, kTones> w{};
  std::vector<std::array<double, kTones>> amp, phase;

  SineChainN(int dofs, unsigned seed, bool free_end = false)
      : n(dofs),
        m(static_cast<std::size_t>(dofs)),
        c(m),
        k(static_cast<std::size_t>(dofs) + 1),
        amp(static_cast<std::size_t>(dofs)),
        phase(amp) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5), ph(0.0, 6.283185307179586);
    for (std::size_t i = 0; i < m.size(); ++i) {
      m[i] = 2.0 * u(gen);
      c[i] = 5.0 * u(gen);
      for (std::size_t q = 0; q < kTones; ++q) {
        amp[i][q] = 1e-3 * u(gen);
        phase[i][q] = ph(gen);
      }
    }
    for (auto& kk : k) kk = 900.0 * u(gen);
    for (std::size_t q = 0; q < kTones; ++q)
      w[q] = 2 * 3.141592653589793 * (2.0 + 5.3 * static_cast<double>(q)) * u(gen);
    if (free_end) k.back() = 0.0;
  }
  double deriv(int i, int order, double t) const {
    if (i < 0 || i >= n) return 0.0;
    const std::size_t a = static_cast<std::size_t>(i);
    double v = 0;
    for (std::size_t q = 0; q < kTones; ++q)
      v += amp[a][q] * std::pow(w[q], order) * std::sin(w[q] * t + phase[a][q] + order * 1.5707963267948966);
    return v;
  }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    const std::size_t a = static_cast<std::size_t>(i);
    return m[a] * deriv(i, 2, t) + c[a] * deriv(i, 1, t) + k[a] * (deriv(i, 0, t) - deriv(i - 1, 0, t)) +
           k[a + 1] * (deriv(i, 0, t) - deriv(i + 1, 0, t));
  }
};

/// The chains with N as a template argument (the fixed-size estimators' tests and the benches).
template <int N>
struct PolynomialChain : PolynomialChainN {
  explicit PolynomialChain(unsigned seed, bool free_end = false) : PolynomialChainN(N, seed, free_end) {}
};
template <int N>
struct SineChain : SineChainN {
  explicit SineChain(unsigned seed) : SineChainN(N, seed) {}
};

/// A record of T samples of a chain (accelerations then forces, T x n row-major), as run() and
/// record() take it.
struct Samples {
  long T = 0;
  int n = 0;
  std::vector<double> accel, force;
  template <class Chain>
  Samples(const Chain& chain, long samples, double dt, double t0 = 0.0)
      : T(samples), n(chain.n), accel(static_cast<std::size_t>(samples * chain.n)), force(accel.size()) {
    for (long s = 0; s < T; ++s)
      for (int i = 0; i < n; ++i) {
        const double t = t0 + static_cast<double>(s) * dt;
        accel[static_cast<std::size_t>(s * n + i)] = chain.accel(i, t);
        force[static_cast<std::size_t>(s * n + i)] = chain.force(i, t);
      }
  }
  const double* a(long s) const { return accel.data() + s * n; }
  const double* u(long s) const { return force.data() + s * n; }
};

}  // namespace algid_test
