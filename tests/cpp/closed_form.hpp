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
//  - OneForceChainN: polynomial trajectories of degree 5 with a force on one DOF only, every
//    other DOF's equation satisfied with u_i = 0 exactly (the scale carried along the springs).
#include <array>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace algid_test {

/// Derivative of order `order` at `t` of the degree-5 polynomial sum c[d] t^d.
inline double poly_derivative(const std::array<double, 6>& c, int order, double t) {
  double v = 0;
  for (int d = order; d < 6; ++d) {
    double f = 1;
    for (int q = 0; q < order; ++q) f *= d - q;
    v += c[static_cast<std::size_t>(d)] * f * std::pow(t, d - order);
  }
  return v;
}

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
    return poly_derivative(coef[static_cast<std::size_t>(i)], order, t);
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

/// A chain forced on one DOF only (`forced`, 0-based), with polynomial trajectories of degree 5
/// that satisfy every unforced DOF's equation (u_i = 0) exactly, so the quadrature is exact as
/// for PolynomialChainN. An unforced DOF's equation gives its neighbour on the far side from the
/// forced DOF, x_(j-+1) = (L_j x_j - k_(j+-1 side) x_(j+-1)) / k_shared, L_j x = m x'' + c x' +
/// (k_j + k_(j+1)) x: from a seed at each end the chain is built inwards to the forced DOF,
/// with constant-coefficient operators Left(D), Right(D) in the seeds. The seeds are Right(D) v
/// at the left end and Left(D) v at the right end, so both sides arrive at the same x_forced
/// (the operators commute; to rounding). Degree 5 is kept (the x term of L_j keeps the degree).
/// The forces of the other DOF are exactly 0.
struct OneForceChainN {
  using Poly = std::array<double, 6>;
  int n, forced;
  std::vector<double> m, c, k;  // n, n, n + 1
  std::vector<Poly> coef;       // x_i(t) = sum coef[i][d] t^d
  /// Time scale of the seed polynomial's terms [s] (coefficient d of order time_scale^-d): the
  /// inertia, damping and spring forces all show within a window of 0.3 s, so the systems are
  /// better conditioned than with coefficients of one order (quasi-static motion).
  static constexpr double kTimeScale = 0.2;

  /// Random parameters as PolynomialChainN draws them.
  OneForceChainN(int dofs, int forced_dof, unsigned seed, bool free_end = false)
      : n(dofs), forced(forced_dof), m(static_cast<std::size_t>(dofs)), c(m), k(static_cast<std::size_t>(dofs) + 1) {
    std::mt19937 gen(seed);
    std::uniform_real_distribution<double> u(0.5, 1.5);
    for (std::size_t i = 0; i < m.size(); ++i) {
      m[i] = 2.0 * u(gen);
      c[i] = 5.0 * u(gen);
    }
    for (auto& kk : k) kk = 900.0 * u(gen);
    if (free_end) k.back() = 0.0;
    build(gen);
  }
  /// Given parameters (e.g. the paper's Table 1).
  OneForceChainN(std::vector<double> mass, std::vector<double> damping, std::vector<double> stiffness, int forced_dof,
                 unsigned seed)
      : n(static_cast<int>(mass.size())),
        forced(forced_dof),
        m(std::move(mass)),
        c(std::move(damping)),
        k(std::move(stiffness)) {
    std::mt19937 gen(seed);
    build(gen);
  }

  double deriv(int i, int order, double t) const {
    return (i < 0 || i >= n) ? 0.0 : poly_derivative(coef[static_cast<std::size_t>(i)], order, t);
  }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    if (i != forced) return 0.0;
    const std::size_t a = static_cast<std::size_t>(i);
    return m[a] * deriv(i, 2, t) + c[a] * deriv(i, 1, t) + k[a] * (deriv(i, 0, t) - deriv(i - 1, 0, t)) +
           k[a + 1] * (deriv(i, 0, t) - deriv(i + 1, 0, t));
  }

 private:
  static Poly axpy(double a, const Poly& x, const Poly& y) {  // a x + y
    Poly out;
    for (std::size_t d = 0; d < 6; ++d) out[d] = a * x[d] + y[d];
    return out;
  }
  // L_j x = m_j x'' + c_j x' + (k_j + k_(j+1)) x
  Poly apply(int j, const Poly& x) const {
    const std::size_t a = static_cast<std::size_t>(j);
    Poly out{};
    for (std::size_t d = 0; d < 6; ++d) {
      out[d] = (k[a] + k[a + 1]) * x[d];
      if (d + 1 < 6) out[d] += c[a] * static_cast<double>(d + 1) * x[d + 1];
      if (d + 2 < 6) out[d] += m[a] * static_cast<double>((d + 2) * (d + 1)) * x[d + 2];
    }
    return out;
  }
  // x_0 .. x_forced from x_0 = seed (DOF 0 .. forced - 1 unforced); x_forced is returned.
  Poly from_left(const Poly& seed, std::vector<Poly>* out) const {
    Poly before{}, x = seed;
    for (int j = 0; j < forced; ++j) {
      if (out) (*out)[static_cast<std::size_t>(j)] = x;
      const Poly next = axpy(-k[static_cast<std::size_t>(j)], before, apply(j, x));
      before = x;
      for (std::size_t d = 0; d < 6; ++d) x[d] = next[d] / k[static_cast<std::size_t>(j) + 1];
    }
    return x;
  }
  // x_(n-1) .. x_forced from x_(n-1) = seed (DOF forced + 1 .. n - 1 unforced).
  Poly from_right(const Poly& seed, std::vector<Poly>* out) const {
    Poly after{}, x = seed;
    for (int j = n - 1; j > forced; --j) {
      if (out) (*out)[static_cast<std::size_t>(j)] = x;
      const Poly next = axpy(-k[static_cast<std::size_t>(j) + 1], after, apply(j, x));
      after = x;
      for (std::size_t d = 0; d < 6; ++d) x[d] = next[d] / k[static_cast<std::size_t>(j)];
    }
    return x;
  }
  void build(std::mt19937& gen) {
    std::uniform_real_distribution<double> s(-1.0, 1.0);
    Poly v;
    for (std::size_t d = 0; d < 6; ++d) v[d] = 1e-3 * s(gen) * std::pow(kTimeScale, -static_cast<double>(d));
    coef.assign(static_cast<std::size_t>(n), Poly{});
    const Poly x_forced = from_left(from_right(v, nullptr), &coef);
    from_right(from_left(v, nullptr), &coef);
    coef[static_cast<std::size_t>(forced)] = x_forced;
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
