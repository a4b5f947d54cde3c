// Quadrature: exact on polynomials of its degree for every iterated order, measured order of
// convergence on a closed-form signal; the Delta-power identity and the eq. 5 row recurrence.
#include <algid/dof_estimator.hpp>
#include <algid/integrator_chain.hpp>

#include "check.hpp"

#include <algorithm>
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
  constexpr int kOrders = 7;
  using Chain = algid::IntegratorChain<P, kOrders>;
  const double h = 0.01;
  typename Chain::Rule rule(h);
  algid::Vector<double, kOrders + 1> pow_inv;
  for (int d = 0; d <= P - 1; ++d) {  // the interpolant of degree P-1 reproduces t^d
    Chain chain;
    chain.reset();
    double worst = 0.0, worst_moment = 0.0;
    for (int k = 0; k < 60; ++k) {
      // relative error from t = 10 h on: before, the values are tiny and rounding of the
      // alternating-sign stencil dominates the comparison
      const double t = k * h;
      if (!chain.push(std::pow(t, d), rule)) continue;
      const double tend = (k - P + 2) * h;
      if (tend < 10 * h) continue;
      for (int r = 1; r <= kOrders; ++r) {
        const double exact = iterated_monomial(d, r, tend);
        worst = std::max(worst, std::abs(chain.integral(r) - exact) / (std::abs(exact) + 1e-30));
      }
      // I^r(Delta^p t^d) = I^r t^(d+p), from the identity on the scaled integrals
      pow_inv(0) = 1.0;
      for (int r = 1; r <= kOrders; ++r) pow_inv(r) = pow_inv(r - 1) / tend;
      typename Chain::Scaled scaled;
      chain.scaled(pow_inv, scaled);
      const double* J = scaled.data();
      for (int p = 0; p <= 2; ++p)
        for (int r = 0; r + p <= kOrders; ++r) {
          const double exact = iterated_monomial(d + p, r, tend) / std::pow(tend, r + p);
          worst_moment = std::max(worst_moment, std::abs(algid::scaled_moment(J, p, r) - exact) / (std::abs(exact) + 1e-30));
        }
    }
    std::printf("P=%d degree %d: worst relative error %.2e (integrals), %.2e (Delta^p moments)\n", P, d, worst,
                worst_moment);
    CHECK(worst < 1e-10);
    CHECK(worst_moment < 1e-9);
  }
}

// The recurrence R(q, s) of signal_rows() against eq. 4-6 written with the moments:
// row operator I^q(Delta^2 f - 4 I(Delta f) + 2 I^2 f), damping I^(q+1)(Delta^2 f) - 2 I^(q+2)(Delta f),
// spring I^(q+2)(Delta^2 f), all divided by their power of tau (pure algebra, any J).
void row_recurrence() {
  double J[8];
  for (int k = 0; k < 8; ++k) J[k] = std::sin(1.3 * k + 0.4) * (1.0 + 0.1 * k);
  algid::Matrix<double, 4, 3> rows;
  algid::signal_rows(J, rows);
  double worst = 0.0;
  for (int q = 0; q < 4; ++q) {
    using algid::scaled_moment;
    const double mass = scaled_moment(J, 2, q) - 4 * scaled_moment(J, 1, q + 1) + 2 * scaled_moment(J, 0, q + 2);
    const double damping = scaled_moment(J, 2, q + 1) - 2 * scaled_moment(J, 1, q + 2);
    const double spring = scaled_moment(J, 2, q + 2);
    worst = std::max({worst, std::abs(rows(q, 0) - mass), std::abs(rows(q, 1) - damping), std::abs(rows(q, 2) - spring)});
  }
  std::printf("row recurrence: worst difference %.2e\n", worst);
  CHECK(worst < 1e-12);
}

// Error of I^r sin(w t) at t = 1 for step h: measured order ~ P.
template <int P>
double chain_error(double h) {
  using Chain = algid::IntegratorChain<P, 5>;
  typename Chain::Rule rule(h);
  Chain chain;
  chain.reset();
  const double w = 7.0;
  const int steps = static_cast<int>(std::lround(1.0 / h)) + P - 2;
  for (int k = 0; k <= steps; ++k) chain.push(std::sin(w * k * h), rule);
  // I^3 sin(w t) from 0 at T = 1: -cos(wT)/w^3 ... closed form via series of the kernel:
  // I^3 f(T) = int_0^T (T - s)^2 / 2 f(s) ds
  const double T = 1.0;
  const double exact = (T * T / (2 * w) - (1 - std::cos(w * T)) / (w * w * w));
  return std::abs(chain.integral(3) - exact);
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
  row_recurrence();
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
