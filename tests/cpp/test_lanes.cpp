// The lane layout's building blocks against their one-value forms: the lane operations
// (vector path against the scalar fallback, NaN semantics of the selects), IntegratorLanes
// (exact on polynomials, one signal per lane, equal to IntegratorChain signal by signal),
// RatioLanes against RatioEstimator, and the lane width rule.
#include <algid/algid.hpp>

#include "check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace {

// The vector path of every lane operation gives, lane by lane, what the scalar expression gives.
template <class Scalar, int W>
void lane_ops_match_scalar() {
  using Ops = algid::detail::LaneOps<Scalar, W>;
  using L = typename Ops::L;
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  L a, b, x, y;
  for (int k = 0; k < W; ++k) {
    a(k) = static_cast<Scalar>(k % 3) - Scalar(1);
    b(k) = static_cast<Scalar>(k % 2);
    x(k) = Scalar(10) + static_cast<Scalar>(k);
    y(k) = Scalar(-20) - static_cast<Scalar>(k);
  }
  a(W - 1) = nan;  // comparisons with NaN are false
  long wrong = 0;
  const L lt = Ops::if_less(a, b, x, y), le = Ops::if_less_equal(a, b, x, y), eq = Ops::if_equal(a, b, x, y);
  const L up = Ops::from_previous(x, y), down = Ops::from_next(x, y);
  const L fma = Ops::madd(x, y, b);
  for (int k = 0; k < W; ++k) {
    wrong += lt(k) != (a(k) < b(k) ? x(k) : y(k));
    wrong += le(k) != (a(k) <= b(k) ? x(k) : y(k));
    wrong += eq(k) != (a(k) == b(k) ? x(k) : y(k));
    wrong += up(k) != (k == 0 ? y(W - 1) : x(k - 1));
    wrong += down(k) != (k == W - 1 ? y(0) : x(k + 1));
    // fused or not, exact here: small integers
    wrong += fma(k) != x(k) * y(k) + b(k);
  }
  std::printf("lane ops, %s x %d (%s): %ld wrong lanes\n", sizeof(Scalar) == 4 ? "float" : "double", W,
              Ops::kVector ? "vector" : "scalar", wrong);
  CHECK(wrong == 0);
  CHECK(lt(W - 1) == y(W - 1) && le(W - 1) == y(W - 1) && eq(W - 1) == y(W - 1));
}

// I^r of f(t) = t^d from 0: d! / (d + r)! t^(d + r)
double iterated_monomial(int d, int r, double t) {
  double v = std::pow(t, d + r);
  for (int i = d + 1; i <= d + r; ++i) v /= i;
  return v;
}

// Signal k = t^(k mod P) in lane k: every lane exact for the degrees the rule reproduces, and
// equal to IntegratorChain of the same signal.
template <int W, int G>
void integrator_lanes_exact() {
  constexpr int P = 8, kOrders = 7, K = W * G;
  const double h = 0.01;
  algid::InterpolatoryRule<P, kOrders> rule(h);
  algid::LaneWeights<P, kOrders, double, W> weights;
  weights.configure(rule);
  algid::IntegratorLanes<P, kOrders, double, W, G> lanes;
  lanes.reset();
  algid::IntegratorChain<P, kOrders, double, K> chain;
  chain.reset();
  double worst = 0, worst_vs_chain = 0;
  double inv_pow[kOrders + 1];
  for (int s = 0; s < 60; ++s) {
    const double t = s * h;
    double f[K];
    for (int k = 0; k < K; ++k) f[k] = std::pow(t, k % P);
    const bool advanced = lanes.push(f, K, weights);
    CHECK(advanced == chain.push(f, rule));
    if (!advanced) continue;
    const double tend = (s - P + 2) * h;
    inv_pow[0] = 1.0;
    for (int r = 1; r <= kOrders; ++r) inv_pow[r] = inv_pow[r - 1] / tend;
    algid::detail::Lanes<double, W> J[G][kOrders + 1];
    for (int g = 0; g < G; ++g) lanes.scaled(g, inv_pow, J[g]);
    for (int k = 0; k < K; ++k) {
      for (int r = 0; r <= kOrders; ++r) {
        const double value = lanes.integral(r, k);
        CHECK(J[k / W][r](k % W) == value * inv_pow[r]);
        if (tend < 10 * h || r == 0) continue;  // tiny values before: rounding of the stencil
        const double reference = chain.integral(r, k);
        worst_vs_chain = std::max(worst_vs_chain, std::abs(value - reference) / std::abs(reference));
        const double exact = iterated_monomial(k % P, r, tend);
        worst = std::max(worst, std::abs(value - exact) / (std::abs(exact) + 1e-30));
      }
    }
  }
  std::printf("IntegratorLanes %d x %d: degrees 0..%d exact to %.2e, equal to IntegratorChain to %.2e\n", W, G, P - 1,
              worst, worst_vs_chain);
  CHECK(worst < 1e-10);
  CHECK(worst_vs_chain < 1e-13);
}

// Eq. 7 of W DOF in lanes against W RatioEstimators (4x4 and 3x3) fed the same samples.
template <int W>
void ratio_lanes_match() {
  using L = algid::detail::Lanes<double, W>;
  algid::RatioLanes<double, W> lanes;
  lanes.reset();
  algid::RatioEstimator<4> full[W];
  algid::RatioEstimator<3> reduced;
  for (auto& r : full) r.reset();
  reduced.reset();
  const double h = 1e-3;
  double worst = 0;
  for (int s = 0; s < 300; ++s) {
    const double prev_tau = s * h, tau = (s + 1) * h;
    const double d4 = algid::RatioEstimator<4>::decay(prev_tau, tau), d3 = algid::RatioEstimator<3>::decay(prev_tau, tau);
    L rho = L::Constant(d4), weight, weighted[4];
    rho(W - 1) = d3;  // the last lane holds a 3x3 DOF
    for (int k = 0; k < W; ++k) {
      weight(k) = (s + k) % 7 == 3 ? 0.0 : 1.0 + std::sin(0.1 * s + k);  // some samples not trusted
      for (int j = 0; j < 4; ++j) weighted[j](k) = weight(k) * (1.0 + j + 0.1 * std::cos(0.05 * s * (j + 1) + k));
    }
    weighted[3](W - 1) = 0.0;
    lanes.add(rho, 0.5 * h, weight, weighted);
    for (int k = 0; k < W; ++k) {
      algid::RatioEstimator<4>::Packed x = algid::RatioEstimator<4>::Packed::Zero();
      x(0) = weight(k);
      for (int j = 0; j < 4; ++j) x(1 + j) = weighted[j](k);
      if (k == W - 1) {
        reduced.add(d3, h, x.head<4>());
        for (int j = 0; j < 3; ++j)
          worst = std::max(worst, std::abs(lanes.numerators()[j](k) / lanes.denominator()(k) - reduced.estimate(j)));
      } else {
        full[k].add(d4, h, x);
        for (int j = 0; j < 4; ++j)
          worst = std::max(worst, std::abs(lanes.numerators()[j](k) / lanes.denominator()(k) - full[k].estimate(j)));
      }
    }
  }
  std::printf("RatioLanes x %d: estimates equal to RatioEstimator to %.2e\n", W, worst);
  CHECK(worst < 1e-13);
}

}  // namespace

int main() {
  lane_ops_match_scalar<double, 1>();
  lane_ops_match_scalar<double, 2>();
  lane_ops_match_scalar<double, 4>();
  lane_ops_match_scalar<double, 8>();
  lane_ops_match_scalar<float, 4>();
  lane_ops_match_scalar<float, 8>();
  integrator_lanes_exact<1, 8>();
  integrator_lanes_exact<2, 4>();
  integrator_lanes_exact<4, 3>();
  ratio_lanes_match<2>();
  ratio_lanes_match<4>();
  // Lane width: a power of two, no wider than needed for N, at most 256 bits.
  constexpr int kDoubleRegister = Eigen::internal::packet_traits<double>::size;
  static_assert(algid::detail::lane_width<1, double>() == 1, "one DOF, one lane");
  static_assert(algid::detail::lane_width<3, double>() == (kDoubleRegister >= 4 ? 4 : kDoubleRegister), "three DOF");
  static_assert(algid::detail::lane_width<50, double>() <= 4 && algid::detail::lane_width<50, float>() <= 8,
                "256-bit lanes at most");
  CHECK(algid::ChainEstimator<3>::kLaneLayout && !algid::ChainEstimator<2>::kLaneLayout);
  return algid_test::finish("test_lanes");
}
