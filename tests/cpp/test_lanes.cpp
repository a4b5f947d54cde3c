// The lane layout's building blocks against plain scalar forms: the lane operations (vector path
// against the scalar fallback, NaN semantics of the selects), IntegratorLanes (exact on
// polynomials, one signal per lane, fixed and run-time register counts, equal to the test
// oracle's plain-loop chain signal by signal), RatioLanes (eq. 7 of W DOF, 4x4 and 3x3, against
// plain trapezoidal double integrals of the physical weights), ratio_decay against pow(), and the
// lane width rule. Built three times: portable flags, -march=x86-64-v3 and -march=x86-64-v4.
#include <algid/algid.hpp>

#include "check.hpp"
#include "oracle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

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

// Signal k = t^(k mod P) in lane k % W of register k / W (K = W * registers signals, the last
// register possibly part-filled): every lane exact for the degrees the rule reproduces, equal to
// the oracle's plain-loop chain of the same signal, and lanes beyond the K signals stay zero.
template <int W, int G>
void integrator_lanes_exact(int registers, int signals) {
  constexpr int P = 8, kOrders = 7;
  const int K = signals;
  const double h = 0.01;
  const algid::InterpolatoryRule<P, kOrders> rule(h);
  algid::LaneWeights<P, kOrders, double, W> weights;
  weights.configure(rule);
  algid::IntegratorLanes<P, kOrders, double, W, G> lanes;
  lanes.configure(registers);
  CHECK(lanes.registers() == registers);
  std::vector<algid_test::ScalarChain<P, kOrders>> plain(static_cast<std::size_t>(K));
  for (auto& c : plain) c.reset();
  double worst = 0, worst_vs_plain = 0;
  long padding = 0;
  double inv_pow[kOrders + 1];
  std::vector<double> f(static_cast<std::size_t>(K));
  std::vector<algid::detail::Lanes<double, W>> J(static_cast<std::size_t>(registers * (kOrders + 1)));
  for (int s = 0; s < 60; ++s) {
    const double t = s * h;
    for (int k = 0; k < K; ++k) f[static_cast<std::size_t>(k)] = std::pow(t, k % P);
    const bool advanced = lanes.push(f.data(), K, weights);
    for (int k = 0; k < K; ++k)
      CHECK(advanced == plain[static_cast<std::size_t>(k)].push(f[static_cast<std::size_t>(k)], rule));
    if (!advanced) continue;
    const double tend = (s - P + 2) * h;
    inv_pow[0] = 1.0;
    for (int r = 1; r <= kOrders; ++r) inv_pow[r] = inv_pow[r - 1] / tend;
    for (int g = 0; g < registers; ++g) lanes.scaled(g, inv_pow, &J[static_cast<std::size_t>(g * (kOrders + 1))]);
    for (int k = 0; k < registers * W; ++k) {
      for (int r = 0; r <= kOrders; ++r) {
        const double value = lanes.integral(r, k);
        CHECK(J[static_cast<std::size_t>(k / W * (kOrders + 1) + r)](k % W) == value * inv_pow[r]);
        if (k >= K) {
          padding += value != 0.0;
          continue;
        }
        const double reference = plain[static_cast<std::size_t>(k)].integral(r);
        if (r == 0) {
          worst_vs_plain = std::max(worst_vs_plain, std::abs(value - reference));
          continue;
        }
        if (tend < 10 * h) continue;  // tiny values before: rounding of the stencil
        worst_vs_plain = std::max(worst_vs_plain, std::abs(value - reference) / std::abs(reference));
        const double exact = iterated_monomial(k % P, r, tend);
        worst = std::max(worst, std::abs(value - exact) / (std::abs(exact) + 1e-30));
      }
    }
  }
  std::printf(
      "IntegratorLanes %d lanes x %d registers%s, %d signals: degrees 0..%d exact to %.2e, equal to the plain "
      "loops to %.2e, %ld non-zero padding values\n",
      W, registers, G == algid::Dynamic ? " (Dynamic)" : "", K, P - 1, worst, worst_vs_plain, padding);
  CHECK(worst < 1e-10);
  CHECK(worst_vs_plain < 1e-13);
  CHECK(padding == 0);
}

// Eq. 7 of W DOF in lanes (the last lane a 3x3 DOF among 4x4 ones, with its own decay factor)
// against plain trapezoidal double integrals of the physical weights |det| tau^q (no rescaling),
// fed the same samples (some not trusted). The decay factors are passed as (prev_tau / tau)^q
// from pow(), so that this checks RatioLanes alone.
template <int W>
void ratio_lanes_match() {
  using L = algid::detail::Lanes<double, W>;
  algid::RatioLanes<double, W> lanes;
  lanes.reset();
  const double h = 1e-3;
  double i1[W][5] = {}, i2[W][5] = {}, prev[W][5] = {};
  double worst = 0;
  for (int s = 0; s < 300; ++s) {
    const double prev_tau = s * h, tau = (s + 1) * h;
    const double d4 = std::pow(prev_tau / tau, 19), d3 = std::pow(prev_tau / tau, 12);
    L rho = L::Constant(d4), weight, weighted[4];
    rho(W - 1) = d3;  // the last lane holds a 3x3 DOF
    for (int k = 0; k < W; ++k) {
      weight(k) = (s + k) % 7 == 3 ? 0.0 : 1.0 + std::sin(0.1 * s + k);  // some samples not trusted
      for (int j = 0; j < 4; ++j) weighted[j](k) = weight(k) * (1.0 + j + 0.1 * std::cos(0.05 * s * (j + 1) + k));
    }
    weighted[3](W - 1) = 0.0;
    lanes.add(rho, 0.5 * h, weight, weighted);
    for (int k = 0; k < W; ++k) {
      const double scale = std::pow(tau, k == W - 1 ? 12 : 19);
      double x[5] = {weight(k) * scale};
      for (int j = 0; j < 4; ++j) x[1 + j] = weighted[j](k) * scale;
      for (int j = 0; j < 5; ++j) {
        const double next = i1[k][j] + 0.5 * h * (prev[k][j] + x[j]);
        i2[k][j] += 0.5 * h * (i1[k][j] + next);
        i1[k][j] = next;
        prev[k][j] = x[j];
      }
      const int m = k == W - 1 ? 3 : 4;
      if (i2[k][0] > 0) CHECK(lanes.denominator()(k) > 0);
      for (int j = 0; j < m; ++j)
        worst = std::max(worst, std::abs(lanes.numerators()[j](k) / lanes.denominator()(k) - i2[k][1 + j] / i2[k][0]));
    }
  }
  std::printf("RatioLanes x %d: eq. 7 equal to the plain double integrals to %.2e\n", W, worst);
  CHECK(worst < 1e-13);
}

// ratio_decay<M>(prev_tau, tau) = (prev_tau / tau)^q, q = kTimeExponent<M> (19 for 4x4, 12 for
// 3x3), on scalars and, lane by lane, on lanes. ratio_decay<3> returns the ninth power: its
// repeated squaring keeps `ratio` unsquared at the first set bit of q when that bit is not bit
// 0 (q = 12 = 0b1100: r^4 is skipped, r * r^8 = r^9 is returned); q = 19 has bit 0 set.
void ratio_decay_exponents() {
  static_assert(algid::kTimeExponent<4> == 19 && algid::kTimeExponent<3> == 12, "det A = det S tau^q");
  double worst4 = 0, worst3 = 0;
  for (int s = 1; s < 200; ++s) {
    const double prev_tau = s * 1e-3, tau = (s + 1) * 1e-3;
    worst4 = std::max(worst4, std::abs(algid::ratio_decay<4>(prev_tau, tau) / std::pow(prev_tau / tau, 19) - 1));
    worst3 = std::max(worst3, std::abs(algid::ratio_decay<3>(prev_tau, tau) / std::pow(prev_tau / tau, 12) - 1));
  }
  const double at_half = algid::ratio_decay<3>(1.0, 2.0);
  std::printf("ratio_decay: 4x4 relative error %.2e; 3x3 %.2e, ratio_decay<3>(1, 2) = %.9g (2^-12 = %.9g)\n", worst4,
              worst3, at_half, std::ldexp(1.0, -12));
  CHECK(worst4 < 1e-13);
  CHECK(algid::ratio_decay<4>(0.0, 1.0) == 0.0 && algid::ratio_decay<3>(0.0, 1.0) == 0.0);  // first sample of a window
  CHECK(worst3 < 1e-13);
  CHECK(at_half == std::ldexp(1.0, -12));
  // lanes: the same value in every lane
  using L = algid::detail::Lanes<double, 4>;
  const L prev = L(0.1, 0.2, 0.3, 0.4), tau = L(0.2, 0.25, 0.31, 1.0);
  const L r4 = algid::ratio_decay<4>(prev, tau), r3 = algid::ratio_decay<3>(prev, tau);
  for (int k = 0; k < 4; ++k) {
    CHECK(r4(k) == algid::ratio_decay<4>(prev(k), tau(k)));
    CHECK(r3(k) == algid::ratio_decay<3>(prev(k), tau(k)));
  }
}

}  // namespace

int main() {
  lane_ops_match_scalar<double, 1>();
  lane_ops_match_scalar<double, 2>();
  lane_ops_match_scalar<double, 4>();
  lane_ops_match_scalar<double, 8>();
  lane_ops_match_scalar<float, 4>();
  lane_ops_match_scalar<float, 8>();
  integrator_lanes_exact<1, 8>(8, 8);
  integrator_lanes_exact<2, 4>(4, 8);
  integrator_lanes_exact<4, 3>(3, 11);  // the last register part-filled: padding lanes
  integrator_lanes_exact<4, algid::Dynamic>(3, 11);
  integrator_lanes_exact<2, algid::Dynamic>(16, 31);
  ratio_lanes_match<2>();
  ratio_lanes_match<4>();
  ratio_decay_exponents();
  // Lane width: a power of two, no wider than needed for N, at most 256 bits; Dynamic takes the
  // widest.
  constexpr int kDoubleRegister = Eigen::internal::packet_traits<double>::size;
  constexpr int kWidest = kDoubleRegister < 4 ? kDoubleRegister : 4;
  static_assert(algid::detail::lane_width<1, double>() == 1, "one DOF, one lane");
  static_assert(algid::detail::lane_width<3, double>() == (kDoubleRegister >= 4 ? 4 : kDoubleRegister), "three DOF");
  static_assert(algid::detail::lane_width<50, double>() <= 4 && algid::detail::lane_width<50, float>() <= 8,
                "256-bit lanes at most");
  static_assert(algid::ChainEstimator<algid::Dynamic>::kLanes == kWidest, "Dynamic: the widest lanes");
  static_assert(algid::ChainEstimator<50>::kLanes == kWidest &&
                    algid::ChainEstimator<50>::kRegisters == (50 + kWidest - 1) / kWidest,
                "registers of DOF");
  static_assert(algid::ChainEstimator<algid::Dynamic, float>::kLanes == algid::detail::lane_width<(1 << 30), float>(),
                "Dynamic float");
  static_assert(algid::ChainEstimator<algid::Dynamic>::kRegisters == algid::Dynamic &&
                    algid::ChainEstimator<algid::Dynamic>::kSpringRegisters == algid::Dynamic,
                "run-time registers");
  std::printf("lane width: double %d (Dynamic), float %d (Dynamic)\n", algid::ChainEstimator<algid::Dynamic>::kLanes,
              algid::ChainEstimator<algid::Dynamic, float>::kLanes);
  return algid_test::finish("test_lanes");
}
