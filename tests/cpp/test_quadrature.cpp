// Quadrature: exact on polynomials of its degree for every iterated order, measured order of
// convergence on a closed-form signal.
#include <algid/integrator_chain.hpp>

#include "check.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

namespace {

// I^r of f(t) = t^d from 0: d! / (d + r)! t^(d + r)
double iterated_monomial(int d, int r, double t) {
  double v = std::pow(t, d + r);
  for (int i = d + 1; i <= d + r; ++i) v /= i;
  return v;
}

template <int P>
void exact_on_polynomials() {
  using Chain = algid::IntegratorChain<P>;
  const double h = 0.01;
  typename Chain::Rule rule(h);
  for (int d = 0; d <= P - 3; ++d) {  // Delta^2 f has degree d + 2 <= P - 1: still exact
    Chain chain;
    chain.reset();
    double worst = 0.0;
    for (int k = 0; k < 60; ++k) {
      // relative error from t = 10 h on: before, the values are tiny and rounding of the
      // alternating-sign stencil dominates the comparison
      const double t = k * h;
      if (!chain.push(std::pow(t, d), t, rule)) continue;
      const double tend = (k - P + 2) * h;
      if (tend < 10 * h) continue;
      for (int p = 0; p < 3; ++p)
        for (int r = 1; r <= 5; ++r) {
          const double exact = iterated_monomial(d + p, r, tend);
          worst = std::max(worst, std::abs(chain(p, r) - exact) / (std::abs(exact) + 1e-30));
        }
    }
    std::printf("P=%d degree %d: worst relative error %.2e\n", P, d, worst);
    CHECK(worst < 1e-10);
  }
}

// Error of I^r sin(w t) at t = 1 for step h: measured order ~ P.
template <int P>
double chain_error(double h) {
  using Chain = algid::IntegratorChain<P>;
  typename Chain::Rule rule(h);
  Chain chain;
  chain.reset();
  const double w = 7.0;
  const int steps = static_cast<int>(std::lround(1.0 / h)) + P - 2;
  for (int k = 0; k <= steps; ++k) chain.push(std::sin(w * k * h), k * h, rule);
  // I^3 sin(w t) from 0 at T = 1: -cos(wT)/w^3 ... closed form via series of the kernel:
  // I^3 f(T) = int_0^T (T - s)^2 / 2 f(s) ds
  const double T = 1.0;
  const double exact = (T * T / (2 * w) - (1 - std::cos(w * T)) / (w * w * w));
  return std::abs(chain(0, 3) - exact);
}

template <int P>
void convergence_order(double h) {
  const double e1 = chain_error<P>(h), e2 = chain_error<P>(h / 2);
  const double order = std::log2(e1 / e2);
  std::printf("P=%d: error %.3e -> %.3e, measured order %.2f\n", P, e1, e2, order);
  CHECK(order > P - 0.6);
  CHECK(order < P + 1.5);
}

}  // namespace

int main() {
  exact_on_polynomials<2>();
  exact_on_polynomials<4>();
  exact_on_polynomials<6>();
  exact_on_polynomials<8>();
  // step pairs chosen so the errors stay far above rounding
  convergence_order<2>(1.0 / 50);
  convergence_order<4>(1.0 / 50);
  convergence_order<6>(1.0 / 32);
  convergence_order<8>(1.0 / 32);
  // The weights of order 1 integrate a constant exactly: they sum to 1 for every offset.
  for (int off = 0; off < 4; ++off) {
    const auto w = algid::InterpolatoryRule<8, 5>::unit_weights(off);
    long double s = 0;
    for (auto x : w[0]) s += x;
    CHECK_NEAR(static_cast<double>(s), 1.0, 1e-15);
  }
  return algid_test::finish("test_quadrature");
}
