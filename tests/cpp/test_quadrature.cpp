// Quadrature, through the integrator chains the estimator runs (IntegratorLanes, here one
// signal in one lane, W = 1, of a fixed or a run-time number of registers): exact on polynomials
// of degree P - 1 for every iterated order, measured order of convergence ~ P on a closed-form
// signal (error ratio ~ 2^P when h is halved); the Delta-power identity (scaled_moment) and the
// eq. 5 row recurrence (signal_row on lanes) against the eq. 4 operators.
#include <algid/algebraic_system.hpp>
#include <algid/integrator_chain.hpp>

#include "check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace {

// I^r of f(t) = t^d from 0: d! / (d + r)! t^(d + r)
double iterated_monomial(int d, int r, double t) {
  double v = std::pow(t, d + r);
  for (int i = d + 1; i <= d + r; ++i) v /= i;
  return v;
}

// One signal through IntegratorLanes<P, Orders, double, 1, G> (G = 1 or Dynamic).
template <int P, int Orders, int G = 1>
struct OneSignal {
  using Rule = algid::InterpolatoryRule<P, Orders>;
  using Chain = algid::IntegratorLanes<P, Orders, double, 1, G>;
  algid::LaneWeights<P, Orders, double, 1> weights;
  Chain chain;
  explicit OneSignal(double h) {
    weights.configure(Rule(h));
    chain.configure(1);
  }
  bool push(double x) { return chain.push(&x, 1, weights); }
  double integral(int r) const { return chain.integral(r, 0); }
  void scaled(const double* inv_pow, double* J) const {
    algid::detail::Lanes<double, 1> lanes[Orders + 1];
    chain.scaled(0, inv_pow, lanes);
    for (int r = 0; r <= Orders; ++r) J[r] = lanes[r](0);
  }
};

template <int P, int G = 1>
void exact_on_polynomials() {
  constexpr int kOrders = 7;
  const double h = 0.01;
  double pow_inv[kOrders + 1];
  for (int d = 0; d <= P - 1; ++d) {  // the interpolant of degree P-1 reproduces t^d
    OneSignal<P, kOrders, G> chain(h);
    CHECK(chain.chain.registers() == 1);
    double worst = 0.0, worst_moment = 0.0;
    long advanced = 0;
    for (int k = 0; k < 60; ++k) {
      // relative error from t = 10 h on: before, the values are tiny and rounding of the
      // alternating-sign stencil dominates the comparison
      const double t = k * h;
      const bool pushed = chain.push(std::pow(t, d));
      CHECK(pushed == (k >= P - 1));  // the first interval end once P samples are in
      CHECK(chain.chain.count() == k + 1);
      if (!pushed) continue;
      ++advanced;
      const double tend = (k - P + 2) * h;
      CHECK(chain.integral(0) == std::pow(tend, d));  // J_0: the sample at the interval end
      if (tend < 10 * h) continue;
      for (int r = 1; r <= kOrders; ++r) {
        const double exact = iterated_monomial(d, r, tend);
        worst = std::max(worst, std::abs(chain.integral(r) - exact) / (std::abs(exact) + 1e-30));
      }
      // I^r(Delta^p t^d) = I^r t^(d+p), from the identity on the scaled integrals
      pow_inv[0] = 1.0;
      for (int r = 1; r <= kOrders; ++r) pow_inv[r] = pow_inv[r - 1] / tend;
      double J[kOrders + 1];
      chain.scaled(pow_inv, J);
      for (int r = 0; r <= kOrders; ++r) CHECK(J[r] == chain.integral(r) * pow_inv[r]);
      for (int p = 0; p <= 2; ++p)
        for (int r = 0; r + p <= kOrders; ++r) {
          const double exact = iterated_monomial(d + p, r, tend) / std::pow(tend, r + p);
          worst_moment = std::max(worst_moment,
                                  std::abs(algid::scaled_moment(J, p, r) - exact) / (std::abs(exact) + 1e-30));
        }
    }
    std::printf("P=%d%s degree %d: worst relative error %.2e (integrals), %.2e (Delta^p moments)\n", P,
                G == algid::Dynamic ? " (Dynamic registers)" : "", d, worst, worst_moment);
    CHECK(advanced == 60 - P + 1);
    CHECK(worst < 1e-10);
    CHECK(worst_moment < 1e-9);
    // reset(): back to t0
    chain.chain.reset();
    CHECK(chain.chain.count() == 0 && !chain.push(1.0));
  }
}

// The recurrence R(q, s) of signal_row() against eq. 4-6 written with the moments:
// row operator I^q(Delta^2 f - 4 I(Delta f) + 2 I^2 f), damping I^(q+1)(Delta^2 f) - 2 I^(q+2)(Delta f),
// spring I^(q+2)(Delta^2 f), all divided by their power of tau (pure algebra, any J); one lane
// and four lanes of different J.
void row_recurrence() {
  using L1 = algid::detail::Lanes<double, 1>;
  using L4 = algid::detail::Lanes<double, 4>;
  double worst = 0.0, worst_lanes = 0.0;
  for (int lane = 0; lane < 4; ++lane) {
    double J[8];
    L1 J1[8];
    L4 J4[8];
    for (int k = 0; k < 8; ++k) {
      J[k] = std::sin(1.3 * k + 0.4 + lane) * (1.0 + 0.1 * k);
      J1[k] = L1::Constant(J[k]);
      for (int b = 0; b < 4; ++b) J4[k](b) = std::sin(1.3 * k + 0.4 + b) * (1.0 + 0.1 * k);
    }
    for (int q = 0; q < 4; ++q) {
      using algid::scaled_moment;
      const double mass = scaled_moment(J, 2, q) - 4 * scaled_moment(J, 1, q + 1) + 2 * scaled_moment(J, 0, q + 2);
      const double damping = scaled_moment(J, 2, q + 1) - 2 * scaled_moment(J, 1, q + 2);
      const double spring = scaled_moment(J, 2, q + 2);
      const double rows[3] = {algid::signal_row(J1, q, q)(0), algid::signal_row(J1, q, q + 1)(0),
                              algid::signal_row(J1, q, q + 2)(0)};
      worst = std::max({worst, std::abs(rows[0] - mass), std::abs(rows[1] - damping), std::abs(rows[2] - spring)});
      for (int c = 0; c < 3; ++c)
        worst_lanes = std::max(worst_lanes, std::abs(algid::signal_row(J4, q, q + c)(lane) - rows[c]));
    }
  }
  std::printf("row recurrence: worst difference %.2e (moments), %.2e (4 lanes against 1)\n", worst, worst_lanes);
  CHECK(worst < 1e-12);
  CHECK(worst_lanes < 1e-15);
  for (int q = 0; q < 4; ++q) CHECK(algid::kRowA[q] == 2 * (q + 2) && algid::kRowB[q] == (q + 2) * (q + 3));
}

// Error of I^3 sin(w t) at t = 1 for step h: measured order ~ P.
template <int P>
double chain_error(double h) {
  OneSignal<P, 5> chain(h);
  const double w = 7.0;
  const int steps = static_cast<int>(std::lround(1.0 / h)) + P - 2;
  for (int k = 0; k <= steps; ++k) chain.push(std::sin(w * k * h));
  // I^3 f(T) = int_0^T (T - s)^2 / 2 f(s) ds = T^2 / (2 w) - (1 - cos(w T)) / w^3
  const double T = 1.0;
  const double exact = (T * T / (2 * w) - (1 - std::cos(w * T)) / (w * w * w));
  return std::abs(chain.integral(3) - exact);
}

template <int P>
void convergence_order(double h) {
  const double e1 = chain_error<P>(h), e2 = chain_error<P>(h / 2);
  const double order = std::log2(e1 / e2);
  std::printf("P=%d: error %.3e -> %.3e when h halves (ratio %.1f, 2^P = %d), measured order %.2f\n", P, e1, e2,
              e1 / e2, 1 << P, order);
  CHECK(order > P - 0.6);
  CHECK(order < P + 1.5);
}

// LaneWeights copies the rule into every lane.
void lane_weights_copy_the_rule() {
  constexpr int P = 8, kOrders = 7;
  const algid::InterpolatoryRule<P, kOrders> rule(1e-3);
  algid::LaneWeights<P, kOrders, double, 4> weights;
  weights.configure(rule);
  long wrong = 0;
  for (int off = 0; off < P / 2; ++off)
    for (int r = 0; r < kOrders; ++r)
      for (int m = 0; m < P; ++m) wrong += (weights.weight(off, r, m) != rule.weights(off)(r, m)).any();
  for (int r = 0; r < kOrders; ++r)
    for (int q = 0; q < kOrders; ++q) wrong += (weights.carry(r, q) != rule.carry()(r, q)).any();
  CHECK(wrong == 0);
  // carry(r, q) = h^(r-q) / (r-q)! below the diagonal, 0 elsewhere
  CHECK_NEAR(rule.carry()(3, 1), 1e-6 / 2, 1e-22);
  CHECK(rule.carry()(1, 1) == 0.0 && rule.carry()(1, 3) == 0.0);
}

}  // namespace

int main() {
  exact_on_polynomials<2>();
  exact_on_polynomials<4>();
  exact_on_polynomials<6>();
  exact_on_polynomials<8>();
  exact_on_polynomials<8, algid::Dynamic>();
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
  lane_weights_copy_the_rule();
  return algid_test::finish("test_quadrature");
}
