// Floating-point operations per DOF-sample, counted by running the real code on a scalar type
// that counts its own arithmetic (ChainEstimator<N, Counted>): additions/subtractions,
// multiplications, divisions and square roots, as the implementation performs them (Eigen's
// scalar path: a dense fixed-size product counts every multiplication, also by a structural
// zero). Sign flips, comparisons, copies and integer work are not counted.
//
//   flop_count            one JSON object per (subject, n) on stdout
//
// Cross-check of the hand count in docs/performance.md; the same counter measures the RLS
// baseline and ChainEstimator<Dynamic, Counted> ("dynamic"). Phases are separated by counting the
// parts of one update through the public IntegratorLanes (the estimator's chains, one lane) and
// signal_row() on one lane with the same inputs.
// Counted and its std overloads must be declared before the core headers: the core calls
// std::isfinite / std::abs / std::sqrt by qualified name.
#include <cmath>
#include <cstdio>
#include <limits>

namespace algid_bench {

struct OpCount {
  long add = 0, mul = 0, div = 0, sqrt = 0;
  long flops() const { return add + mul + div + sqrt; }
};
inline OpCount g_ops;

/// A double that counts the arithmetic done on it.
class Counted {
 public:
  Counted() = default;
  Counted(double v) : v_(v) {}  // NOLINT: implicit, like a built-in floating type
  Counted(long double v) : v_(static_cast<double>(v)) {}
  Counted(float v) : v_(v) {}
  Counted(int v) : v_(v) {}
  Counted(long v) : v_(static_cast<double>(v)) {}
  explicit operator double() const { return v_; }
  explicit operator float() const { return static_cast<float>(v_); }
  explicit operator long double() const { return v_; }
  double value() const { return v_; }

  friend Counted operator+(Counted a, Counted b) {
    ++g_ops.add;
    return Counted(a.v_ + b.v_);
  }
  friend Counted operator-(Counted a, Counted b) {
    ++g_ops.add;
    return Counted(a.v_ - b.v_);
  }
  friend Counted operator*(Counted a, Counted b) {
    ++g_ops.mul;
    return Counted(a.v_ * b.v_);
  }
  friend Counted operator/(Counted a, Counted b) {
    ++g_ops.div;
    return Counted(a.v_ / b.v_);
  }
  friend Counted operator-(Counted a) { return Counted(-a.v_); }
  friend Counted operator+(Counted a) { return a; }
  Counted& operator+=(Counted b) { return *this = *this + b; }
  Counted& operator-=(Counted b) { return *this = *this - b; }
  Counted& operator*=(Counted b) { return *this = *this * b; }
  Counted& operator/=(Counted b) { return *this = *this / b; }
  friend bool operator<(Counted a, Counted b) { return a.v_ < b.v_; }
  friend bool operator>(Counted a, Counted b) { return a.v_ > b.v_; }
  friend bool operator<=(Counted a, Counted b) { return a.v_ <= b.v_; }
  friend bool operator>=(Counted a, Counted b) { return a.v_ >= b.v_; }
  friend bool operator==(Counted a, Counted b) { return a.v_ == b.v_; }
  friend bool operator!=(Counted a, Counted b) { return a.v_ != b.v_; }

 private:
  double v_ = 0;
};

}  // namespace algid_bench

// The core calls std::isfinite / std::abs / std::sqrt on its Scalar; a bench-only overload set.
namespace std {
inline bool isfinite(algid_bench::Counted x) { return std::isfinite(x.value()); }
inline bool isnan(algid_bench::Counted x) { return std::isnan(x.value()); }
inline algid_bench::Counted abs(algid_bench::Counted x) { return algid_bench::Counted(std::fabs(x.value())); }
inline algid_bench::Counted sqrt(algid_bench::Counted x) {
  ++algid_bench::g_ops.sqrt;
  return algid_bench::Counted(std::sqrt(x.value()));
}
template <>
class numeric_limits<algid_bench::Counted> : public numeric_limits<double> {
 public:
  static algid_bench::Counted quiet_NaN() { return numeric_limits<double>::quiet_NaN(); }
  static algid_bench::Counted infinity() { return numeric_limits<double>::infinity(); }
  static algid_bench::Counted epsilon() { return numeric_limits<double>::epsilon(); }
  static algid_bench::Counted min() { return numeric_limits<double>::min(); }
  static algid_bench::Counted max() { return numeric_limits<double>::max(); }
  static algid_bench::Counted lowest() { return numeric_limits<double>::lowest(); }
};
}  // namespace std

#include <Eigen/Core>

namespace Eigen {
template <>
struct NumTraits<algid_bench::Counted> : GenericNumTraits<algid_bench::Counted> {
  using Real = algid_bench::Counted;
  using NonInteger = algid_bench::Counted;
  using Nested = algid_bench::Counted;
  using Literal = algid_bench::Counted;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 1,
    MulCost = 1
  };
  static Real epsilon() { return std::numeric_limits<double>::epsilon(); }
  static Real dummy_precision() { return 1e-12; }
  static Real highest() { return std::numeric_limits<double>::max(); }
  static Real lowest() { return std::numeric_limits<double>::lowest(); }
  static int digits10() { return std::numeric_limits<double>::digits10; }
};
}  // namespace Eigen

#include <algid/algid.hpp>

#include "rls.hpp"
#include "signals.hpp"

namespace {

using algid_bench::Counted;
using algid_bench::g_ops;

void print(const char* subject, int n, long samples, const algid_bench::OpCount& c) {
  const double per = static_cast<double>(samples) * n;
  std::printf(
      "{\"subject\": \"%s\", \"n\": %d, \"flops_per_dof_sample\": %.2f, \"add\": %.2f, \"mul\": %.2f, "
      "\"div\": %.2f, \"sqrt\": %.2f}\n",
      subject, n, static_cast<double>(c.flops()) / per, static_cast<double>(c.add) / per,
      static_cast<double>(c.mul) / per, static_cast<double>(c.div) / per, static_cast<double>(c.sqrt) / per);
}

constexpr int kWarm = 64;
constexpr int kCounted = 512;

template <int N, bool Dyn = false>
void count_estimator() {
  const auto sig = algid_bench::make_signals<N, double>(kWarm + kCounted);
  using Est = algid::ChainEstimator<Dyn ? algid::Dynamic : N, Counted>;
  typename Est::Config cfg;
  cfg.dt = Counted(algid_bench::kDt);
  Est est(cfg, N);
  Counted a[N], u[N];
  auto feed = [&](int k) {
    for (int i = 0; i < N; ++i) {
      a[i] = Counted(sig.accel[static_cast<std::size_t>(k * N + i)]);
      u[i] = Counted(sig.force[static_cast<std::size_t>(k * N + i)]);
    }
    est.update(a, u);
  };
  for (int k = 0; k < kWarm; ++k) feed(k);
  g_ops = {};
  for (int k = kWarm; k < kWarm + kCounted; ++k) feed(k);
  print(Dyn ? "dynamic" : "default", N, kCounted, g_ops);
}

// The phases of one DOF-sample of a 3-DOF chain (here one lane per register: the counting
// scalar has no SIMD packets, so this counts the useful work, without the padding lanes of the
// SIMD builds): the integrator chains of the accelerations and forces, the time scaling and the
// eq. 5 rows (signal_row(), as ChainEstimator forms them: mass, damping and spring rows of each
// acceleration, the rows of each force, q = 0..3), and the rest of update() (systems, Cramer,
// Hadamard ratio, validity, eq. 7, estimates, spring fusion) as the total minus both.
void count_phases() {
  constexpr int N = 3;
  constexpr int P = 8;
  using Est = algid::ChainEstimator<N, Counted>;
  static_assert(Est::kLanes == 1, "the counting scalar has no packets: one lane");
  using L1 = algid::detail::Lanes<Counted, 1>;
  const auto sig = algid_bench::make_signals<N, double>(kWarm + kCounted);
  typename Est::Rule rule(Counted(algid_bench::kDt));
  algid::LaneWeights<P, algid::kAccelOrders, Counted, 1> weights;
  weights.configure(rule);
  algid::IntegratorLanes<P, algid::kAccelOrders, Counted, 1, N> ya;
  algid::IntegratorLanes<P, algid::kForceOrders, Counted, 1, N> fa;
  ya.configure(N);
  fa.configure(N);
  typename Est::Config cfg;
  cfg.dt = Counted(algid_bench::kDt);
  Est est(cfg);
  algid_bench::OpCount push{}, rows{}, total{};
  const auto add = [](algid_bench::OpCount& to, long div) {
    to.add += g_ops.add / div, to.mul += g_ops.mul / div, to.div += g_ops.div / div, to.sqrt += g_ops.sqrt / div;
  };
  for (int k = 0; k < kWarm + kCounted; ++k) {
    const bool counting = k >= kWarm;
    Counted a[N], u[N];
    for (int i = 0; i < N; ++i) {
      a[i] = Counted(sig.accel[static_cast<std::size_t>(k * N + i)]);
      u[i] = Counted(sig.force[static_cast<std::size_t>(k * N + i)]);
    }
    g_ops = {};
    est.update(a, u);
    if (counting) add(total, N);
    g_ops = {};
    const bool advanced = ya.push(a, N, weights);
    fa.push(u, N, weights);
    if (counting) add(push, N);
    if (!advanced) continue;
    const double tau = static_cast<double>(k + 1 - P + 1) * algid_bench::kDt;
    Counted inv_pow[algid::kAccelOrders + 1];
    inv_pow[0] = Counted(1.0);
    for (int r = 1; r <= algid::kAccelOrders; ++r) inv_pow[r] = Counted(inv_pow[r - 1].value() / tau);
    g_ops = {};
    for (int g = 0; g < N; ++g) {
      L1 JA[algid::kAccelOrders + 1], JF[algid::kForceOrders + 1];
      ya.scaled(g, inv_pow, JA);
      fa.scaled(g, inv_pow, JF);
      for (int q = 0; q < 4; ++q) {  // the counted operations happen whether or not a row is used
        (void)algid::signal_row(JA, q, q);
        (void)algid::signal_row(JA, q, q + 1);
        (void)algid::signal_row(JA, q, q + 2);
        (void)algid::signal_row(JF, q, q);
      }
    }
    if (counting) add(rows, N);
  }
  algid_bench::OpCount rest{total.add - push.add - rows.add, total.mul - push.mul - rows.mul,
                            total.div - push.div - rows.div, total.sqrt - push.sqrt - rows.sqrt};
  print("phase:chain_banks_accel_and_force", 1, kCounted, push);
  print("phase:time_scaling_and_rows", 1, kCounted, rows);
  print("phase:dof_update(systems+cramer+hadamard+validity+eq7+fusion)", 1, kCounted, rest);
  // Cramer alone, and eq. 7 alone, on one system.
  Counted S[16], b[4], det, numerator[4];
  for (int e = 0; e < 16; ++e) S[e] = Counted(1.0 + e % 5 + (e % 4 == e / 4 ? 3.0 : 0.0));
  for (int q = 0; q < 4; ++q) b[q] = Counted(1.0 + q);
  g_ops = {};
  algid::cramer_lanes4(S, b, det, numerator);
  print("phase:cramer_4x4", 1, 1, g_ops);
  using L1 = algid::detail::Lanes<Counted, 1>;
  algid::RatioLanes<Counted, 1> ratio;
  ratio.reset();
  const L1 weighted[4] = {L1::Constant(numerator[0]), L1::Constant(numerator[1]), L1::Constant(numerator[2]),
                          L1::Constant(numerator[3])};
  ratio.add(L1::Constant(Counted(0.0)), Counted(0.5e-3), L1::Constant(Counted(1.0)), weighted);
  g_ops = {};
  ratio.add(L1::Constant(Counted(0.9)), Counted(0.5e-3), L1::Constant(Counted(1.0)), weighted);
  print("phase:eq7_ratio_add", 1, 1, g_ops);
}

template <int N>
void count_rls() {
  const auto sig = algid_bench::make_signals<N, double>(kWarm + kCounted);
  algid_bench::Rls4<Counted> rls[N];
  Counted phi[4];
  auto feed = [&](int k) {
    for (int i = 0; i < N; ++i) {
      for (int j = 0; j < 4; ++j) phi[j] = Counted(sig.phi[static_cast<std::size_t>(4 * (k * N + i) + j)]);
      rls[i].update(phi, Counted(sig.force[static_cast<std::size_t>(k * N + i)]));
    }
  };
  for (int k = 0; k < kWarm; ++k) feed(k);
  g_ops = {};
  for (int k = kWarm; k < kWarm + kCounted; ++k) feed(k);
  print("rls", N, kCounted, g_ops);
}

}  // namespace

int main() {
  count_estimator<1>();
  count_estimator<3>();
  count_estimator<10>();
  count_estimator<50>();
  count_estimator<1, true>();
  count_estimator<3, true>();
  count_estimator<50, true>();
  count_rls<3>();
  count_phases();
  return 0;
}
