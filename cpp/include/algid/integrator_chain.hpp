#pragma once
/// @file integrator_chain.hpp
/// The iterated integrator chain of eq. 6 for one measured signal, and the identity that
/// turns it into every integral eqs. 4-6 need.
///
/// For a signal f sampled at t_k = t_0 + k h the chain keeps, at the interval end t_{j+1},
///
///   I^r f (t_{j+1}),   r = 1 .. Orders,
///
/// the r-fold integral from t_0 (zero initial conditions, eq. 6), advanced with the
/// interpolatory rule of quadrature.hpp; r = 0 is the sample itself. The rule needs P samples
/// around each interval, so the chain reports the instant t_{j+1} = t_k - (P-2) h when sample k
/// arrives.
///
/// Eq. 4 multiplies the signals by powers of Delta = t - t_0 before integrating. Those
/// integrals are not advanced separately: integration by parts gives, exactly,
///
///   I^r(Delta^p f) = sum_{k=0..p} (-1)^k C(p, k) r (r+1) .. (r+k-1) Delta^(p-k) I^(r+k) f,
///
/// (p = 1: I^r(Delta f) = Delta I^r f - r I^(r+1) f), so one chain of f up to order r + p
/// serves every power. Divided by tau^(r+p) (tau = Delta at the instant) the right-hand side
/// only involves the time-scaled integrals J_k = I^k f / tau^k, with integer coefficients:
/// see `scaled_moment()`. Compared with integrating Delta^p f directly, this is exact for
/// polynomial signals of degree P-1 (not P-1-p) and costs a third of the work.

#include "algid/detail/lanes.hpp"
#include "algid/quadrature.hpp"
#include "algid/types.hpp"

#include <algorithm>
#include <array>
#include <cstddef>

namespace algid {
namespace detail {

/// state += step, Kahan-compensated (`compensation` carries the lost low-order part) when
/// Compensated; scalars, Eigen matrices or arrays alike.
template <bool Compensated, class T, class C>
inline void accumulate(T& state, C& compensation, const T& step) noexcept {
  if constexpr (Compensated) {
    const T y = step - compensation;
    const T t = state + y;
    compensation = (t - state) - y;
    state = t;
  } else {
    (void)compensation;
    state += step;
  }
}

}  // namespace detail

/// Iterated integrals I^1 .. I^Orders of K sampled signals that share one clock (the
/// accelerations, or the forces, of a chain): one stencil offset and one rule for all; each
/// signal's orders advance in SIMD registers of at most 256 bits (the stencil's weighted sum
/// and the Taylor carry as fused multiply-adds where the build has them), and a block of
/// samples can advance with the weights held in registers (push_steady()).
/// Storage: a doubled ring of 2P samples per signal (any stencil is a contiguous block), the
/// Orders x K states and, in single precision, their Kahan compensation; nothing else. Do not
/// build with -ffast-math (it would remove the compensation).
/// @tparam P interpolation points of the quadrature (see InterpolatoryRule).
/// @tparam Orders highest order of iterated integral kept (a multiple of the SIMD width is
/// cheapest: a padding order costs nothing and is a valid integral).
/// @tparam K number of signals.
template <int P, int Orders, class Scalar = double, int K = 1>
class IntegratorChain {
  static_assert(Orders >= 1, "at least one integral");
  static_assert(K >= 1, "at least one signal");

 public:
  /// Highest order of iterated integral kept.
  static constexpr int kOrders = Orders;
  /// Kahan-compensated state update: on for single precision (where the state, growing like
  /// tau^r, otherwise loses the small per-step increments), off for double.
  static constexpr bool kCompensated = sizeof(Scalar) < sizeof(double);
  /// The smallest rule this chain can be advanced with (a rule of more orders works too).
  using Rule = InterpolatoryRule<P, Orders, Scalar>;
  /// Time-scaled integrals of every signal: column k holds J_0 .. J_Orders of signal k.
  using Scaled = Matrix<Scalar, Orders + 1, K>;

  /// Forget everything: the next sample is t_0. @realtime no allocation, no throw.
  void reset() noexcept {
    count_ = 0;
    value_.setZero();
    state_.setZero();
    compensation_.setZero();
  }

  /// Consume the simultaneous samples f[0..K-1]. Returns true when the chains have advanced to
  /// a new interval end (from the P-th sample on). @realtime no allocation, no throw.
  template <int RuleOrders>
  bool push(const Scalar* f, const InterpolatoryRule<P, RuleOrders, Scalar>& rule) noexcept {
    static_assert(RuleOrders >= Orders, "the rule must cover every order of the chain");
    store(f);
    if (count_ < P) return false;
    const long j = count_ - P;  // interval [t_j, t_{j+1}]
    const long start = Rule::stencil_start(j);
    const WeightsInMemory<RuleOrders> w{&rule, static_cast<int>(j - start)};
    const int first = static_cast<int>(start % kRing);
    for (int k = 0; k < K; ++k) {
      Packet s[kRegs], c[kRegs];
      load_state(k, s, c);
      advance(w, first, k, s, c);
      store_state(k, s, c);
    }
    value_ = ring_.row(static_cast<int>((j + 1) % kRing)).transpose();
    return true;
  }

  /// B calls of push() in a row past the start-up (every stencil centred: steady()) for C
  /// chains of this type that share one rule and one clock (a chain's accelerations and its
  /// forces), with the rule's weights and the states held in registers from sample to sample
  /// and the C independent recurrences interleaved sample by sample: the same arithmetic as
  /// push(), the same bits. Chain i's sample b is f[i][b * stride + k], k < K; after it, its
  /// states are written to states[i] + b * Orders * K (Orders x K, column-major, as state())
  /// and its values to values[i] + b * K (as value()). @realtime no allocation, no throw.
  template <int B, int C, int RuleOrders>
  static void push_steady(const std::array<IntegratorChain*, C>& chains, const std::array<const Scalar*, C>& f,
                          int stride, const InterpolatoryRule<P, RuleOrders, Scalar>& rule,
                          const std::array<Scalar*, C>& states, const std::array<Scalar*, C>& values) noexcept {
    static_assert(RuleOrders >= Orders, "the rule must cover every order of the chain");
    const Weights w = weights(rule, Rule::kOffsets - 1);
    Packet s[C][K][kRegs], c[C][K][kRegs];
    for (int i = 0; i < C; ++i)
      for (int k = 0; k < K; ++k) chains[i]->load_state(k, s[i][k], c[i][k]);
    // Ring rows as unsigned counts (count_ >= P - 1 here, the same for every chain): the
    // stencil's first sample (centred: j - (P/2 - 1)) and the interval end j + 1, for
    // j = count_ - P after the sample is stored.
    const unsigned long base = static_cast<unsigned long>(chains[0]->count_);
    for (int b = 0; b < B; ++b) {
      const unsigned long pushed = base + static_cast<unsigned long>(b);  // samples before this one
      const int first = static_cast<int>((pushed + 1 - P - (P / 2 - 1)) % kRing);
      const int now = static_cast<int>((pushed + 2 - P) % kRing);
      for (int i = 0; i < C; ++i) {
        IntegratorChain& chain = *chains[i];
        chain.store(f[i] + b * stride);
        for (int k = 0; k < K; ++k) {
          chain.advance(w, first, k, s[i][k], c[i][k]);
          for (int g = 0; g < kRegs; ++g)
            Eigen::internal::pstoreu(states[i] + (b * K + k) * Orders + g * kPW, s[i][k][g]);
          values[i][b * K + k] = chain.ring_(now, k);
        }
      }
    }
    for (int i = 0; i < C; ++i) {
      IntegratorChain& chain = *chains[i];
      for (int k = 0; k < K; ++k) chain.store_state(k, s[i][k], c[i][k]);
      chain.value_ = Eigen::Map<const Vector<Scalar, K>>(values[i] + (B - 1) * K);
    }
  }

  /// Whether the next push() advances with a centred stencil (past the start-up), the case of
  /// push_steady().
  bool steady() const noexcept { return count_ + 1 - P >= Rule::kOffsets - 1; }

  /// push() for a single signal (K = 1). @realtime no allocation, no throw.
  template <int RuleOrders>
  bool push(Scalar f, const InterpolatoryRule<P, RuleOrders, Scalar>& rule) noexcept {
    static_assert(K == 1, "one sample per signal");
    return push(&f, rule);
  }

  /// I^r f_k at the current interval end, r = 0 .. Orders; r = 0 is the sample value itself.
  Scalar integral(int r, int k = 0) const noexcept { return r == 0 ? value_(k) : state_(r - 1, k); }

  /// Time-scaled integrals J_r = I^r f_k / tau^r, r = 0 .. Orders, of every signal, given
  /// inv_tau_pow(r) = tau^-r. @realtime no allocation, no throw.
  template <class Derived>
  void scaled(const Eigen::MatrixBase<Derived>& inv_tau_pow, Scaled& out) const noexcept {
    out.row(0) = value_.transpose();
    out.template bottomRows<Orders>().noalias() =
        inv_tau_pow.template segment<Orders>(1).asDiagonal() * state_;
  }

  /// I^1 .. I^Orders of every signal (row r - 1: order r) at the current interval end.
  const Matrix<Scalar, Orders, K>& state() const noexcept { return state_; }
  /// The signals' samples at the current interval end (I^0).
  const Vector<Scalar, K>& value() const noexcept { return value_; }

  /// Samples consumed since the last reset.
  long count() const noexcept { return count_; }

 private:
  // The orders of a signal in registers (Packet) of at most 256 bits, as the lane layout.
  using Packet = typename detail::DividingPacket<Scalar, Orders>::type;
  static constexpr int kPW = Eigen::internal::unpacket_traits<Packet>::size;
  static constexpr int kRegs = Orders / kPW;
  static_assert(Orders % kPW == 0, "whole registers of orders");

  // The weights of one stencil offset and the carry, as registers (for a block of pushes):
  // tap m of orders g kPW .. (g + 1) kPW - 1 in w[m][g], carry column q in c[q][g] (q < Orders
  // - 1; the last is zero).
  struct Weights {
    Packet w[P][kRegs];
    Packet c[Orders > 1 ? Orders - 1 : 1][kRegs];
    Packet tap(int m, int g) const noexcept { return w[m][g]; }
    Packet carry(int q, int g) const noexcept { return c[q][g]; }
  };
  // The same, read from the rule where they are used (a single push: no copy).
  template <int RuleOrders>
  struct WeightsInMemory {
    const InterpolatoryRule<P, RuleOrders, Scalar>* rule;
    int off;
    Packet tap(int m, int g) const noexcept { return Eigen::internal::ploadu<Packet>(&rule->weights(off)(g * kPW, m)); }
    Packet carry(int q, int g) const noexcept { return Eigen::internal::ploadu<Packet>(&rule->carry()(g * kPW, q)); }
  };
  template <int RuleOrders>
  static Weights weights(const InterpolatoryRule<P, RuleOrders, Scalar>& rule, int off) noexcept {
    Weights out;
    for (int m = 0; m < P; ++m)
      for (int g = 0; g < kRegs; ++g) out.w[m][g] = Eigen::internal::ploadu<Packet>(&rule.weights(off)(g * kPW, m));
    for (int q = 0; q + 1 < Orders; ++q)
      for (int g = 0; g < kRegs; ++g) out.c[q][g] = Eigen::internal::ploadu<Packet>(&rule.carry()(g * kPW, q));
    return out;
  }

  // The new sample into both copies of the ring.
  void store(const Scalar* f) noexcept {
    const int slot = static_cast<int>(static_cast<unsigned long>(count_) % kRing);  // count_ >= 0
    for (int k = 0; k < K; ++k) {
      ring_(slot, k) = f[k];
      ring_(slot + kRing, k) = f[k];
    }
    ++count_;
  }
  void load_state(int k, Packet* s, Packet* c) const noexcept {
    for (int g = 0; g < kRegs; ++g) {
      s[g] = Eigen::internal::ploadu<Packet>(&state_(g * kPW, k));
      if constexpr (kCompensated) c[g] = Eigen::internal::ploadu<Packet>(&compensation_(g * kPW, k));
    }
  }
  void store_state(int k, const Packet* s, const Packet* c) noexcept {
    for (int g = 0; g < kRegs; ++g) {
      Eigen::internal::pstoreu(&state_(g * kPW, k), s[g]);
      if constexpr (kCompensated) Eigen::internal::pstoreu(&compensation_(g * kPW, k), c[g]);
    }
  }

  // Signal k over one interval, its states in s (and their compensation in c):
  //   I^r += h^r sum_m W(r, m) f_m + sum_{q<r} h^(r-q)/(r-q)! I^q,
  // every order from the old lower orders (the step is computed whole before the state moves),
  // the stencil's samples from ring row `first` on.
  template <class W>
  void advance(const W& w, int first, int k, Packet* s, Packet* c) const noexcept {
    using namespace Eigen::internal;
    const Scalar* f = &ring_(first, k);
    Scalar old[Orders];  // the lower orders, one at a time for the carry
    for (int g = 0; g < kRegs; ++g) pstoreu(old + g * kPW, s[g]);
    Packet step[kRegs];
    for (int g = 0; g < kRegs; ++g) {
      step[g] = pmul(w.tap(0, g), pset1<Packet>(f[0]));
      for (int m = 1; m < P; ++m) step[g] = pmadd(w.tap(m, g), pset1<Packet>(f[m]), step[g]);
      // The carry, the part that depends on the state: in three partial sums, so that the
      // chain of dependent operations from one sample's state to the next is short (the
      // weighted samples above do not wait for the state). carry(r, q) = 0 for q >= r:
      // register g needs q <= (g + 1) kPW - 2.
      const int last = std::min(Orders - 2, (g + 1) * kPW - 2);
      Packet part[2];
      for (int q = 0; q <= last; ++q) {
        const Packet weight = w.carry(q, g), lower = pset1<Packet>(old[q]);
        if (q % 3 == 0) {
          step[g] = pmadd(weight, lower, step[g]);
        } else if (q < 3) {
          part[q - 1] = pmul(weight, lower);
        } else {
          part[q % 3 - 1] = pmadd(weight, lower, part[q % 3 - 1]);
        }
      }
      if (last >= 2) {
        step[g] = padd(step[g], padd(part[0], part[1]));
      } else if (last == 1) {
        step[g] = padd(step[g], part[0]);
      }
    }
    // The state grows like tau^r while each step adds a small amount: that is where single
    // precision loses its digits (Kahan-compensated there); double keeps them without.
    for (int g = 0; g < kRegs; ++g) {
      if constexpr (kCompensated) {
        const Packet y = psub(step[g], c[g]);
        const Packet t = padd(s[g], y);
        c[g] = psub(psub(t, s[g]), y);
        s[g] = t;
      } else {
        s[g] = padd(s[g], step[g]);
      }
    }
  }

  static constexpr int kRing = 2 * P;  // >= 3P/2 - 1 samples: a centred stencil's span
  Matrix<Scalar, 2 * kRing, K> ring_ = Matrix<Scalar, 2 * kRing, K>::Zero();
  Matrix<Scalar, Orders, K> state_ = Matrix<Scalar, Orders, K>::Zero();
  // Kahan compensation: single precision only (a 1 x 1 placeholder otherwise)
  Matrix<Scalar, kCompensated ? Orders : 1, kCompensated ? K : 1> compensation_ =
      Matrix<Scalar, kCompensated ? Orders : 1, kCompensated ? K : 1>::Zero();
  Vector<Scalar, K> value_ = Vector<Scalar, K>::Zero();
  long count_ = 0;
};

/// The same iterated integrals in the lane layout: up to G W signals that share one clock, one
/// signal per SIMD lane (signal k in lane k % W of register k / W), so that one register
/// operation advances W signals; the layout of ChainEstimator for chains of three DOF or more,
/// whose DOF are solved side by side (one per lane) from these integrals. Each lane follows the
/// recurrence of IntegratorChain with the same rule; the sums are formed with fused
/// multiply-adds where the build has them. Lanes beyond the signals pushed stay zero.
/// Storage: a doubled ring of 2P samples and the Orders states per lane register (and, in
/// single precision, their Kahan compensation). Do not build with -ffast-math.
/// @tparam P interpolation points of the quadrature.
/// @tparam Orders highest order of iterated integral kept.
/// @tparam W lanes per register, G registers.
template <int P, int Orders, class Scalar, int W, int G>
class IntegratorLanes {
  static_assert(Orders >= 1, "at least one integral");
  static_assert(W >= 1 && G >= 1, "at least one lane");

 public:
  using L = detail::Lanes<Scalar, W>;
  /// Highest order of iterated integral kept.
  static constexpr int kOrders = Orders;
  /// Kahan-compensated state update in single precision (see IntegratorChain).
  static constexpr bool kCompensated = sizeof(Scalar) < sizeof(double);

  /// Forget everything: the next sample is t_0. @realtime no allocation, no throw.
  void reset() noexcept {
    count_ = 0;
    now_ = 0;
    for (auto& slot : ring_)
      for (auto& x : slot) x.setZero();
    for (auto& order : state_)
      for (auto& x : order) x.setZero();
    for (auto& order : compensation_)
      for (auto& x : order) x.setZero();
  }

  /// Consume the simultaneous samples f[0 .. n-1] (n <= G W) of the signals in lanes 0 .. n-1.
  /// Returns true when the integrals have advanced to a new interval end (from the P-th
  /// sample on). @realtime no allocation, no throw.
  template <int RuleOrders>
  bool push(const Scalar* f, int n, const LaneWeights<P, RuleOrders, Scalar, W>& rule) noexcept {
    static_assert(RuleOrders >= Orders, "the rule must cover every order of the chain");
    const int slot = static_cast<int>(count_ % kRing);
    auto& copy0 = ring_[static_cast<std::size_t>(slot)];
    auto& copy1 = ring_[static_cast<std::size_t>(slot + kRing)];
    for (int k = 0; k < n; ++k) {
      copy0[static_cast<std::size_t>(k / W)](k % W) = f[k];
      copy1[static_cast<std::size_t>(k / W)](k % W) = f[k];
    }
    ++count_;
    if (count_ < P) return false;
    const long j = count_ - P;  // interval [t_j, t_{j+1}]
    const long start = InterpolatoryRule<P, Orders, Scalar>::stencil_start(j);
    const int off = static_cast<int>(j - start);
    const auto* stencil = &ring_[static_cast<std::size_t>(start % kRing)];
    now_ = static_cast<int>((j + 1) % kRing);
    using Ops = detail::LaneOps<Scalar, W>;
    for (int g = 0; g < G; ++g) {
      // Every order from the old lower orders: the step is computed whole before the state moves.
      L step[Orders];
      detail::static_for<0, Orders>([&](auto order) {
        constexpr int r = decltype(order)::value;  // unrolled: the carry below has r terms
        L acc = stencil[0][g] * rule.weight(off, r, 0);
        for (int m = 1; m < P; ++m) acc = Ops::madd(stencil[m][g], rule.weight(off, r, m), acc);
        for (int q = 0; q < r; ++q) acc = Ops::madd(state_[q][g], rule.carry(r, q), acc);
        step[r] = acc;
      });
      for (int r = 0; r < Orders; ++r)
        detail::accumulate<kCompensated>(state_[r][g], compensation_[kCompensated ? r : 0][g], step[r]);
    }
    return true;
  }

  /// Time-scaled integrals J_r = I^r f / tau^r, r = 0 .. Orders, of the signals of register g
  /// at the current interval end, given inv_tau_pow[r] = tau^-r (J_0 is the sample itself).
  /// @realtime no allocation, no throw.
  void scaled(int g, const Scalar* inv_tau_pow, L* J) const noexcept {
    J[0] = ring_[static_cast<std::size_t>(now_)][g];
    for (int r = 1; r <= Orders; ++r) J[r] = inv_tau_pow[r] * state_[r - 1][g];
  }

  /// I^r of the signal in lane k (r = 0: the sample) at the current interval end.
  Scalar integral(int r, int k) const noexcept {
    const L& x = r == 0 ? ring_[static_cast<std::size_t>(now_)][k / W] : state_[r - 1][k / W];
    return x(k % W);
  }

  /// Samples consumed since the last reset.
  long count() const noexcept { return count_; }

 private:
  static constexpr int kRing = 2 * P;  // >= 3P/2 - 1 samples: a centred stencil's span
  std::array<std::array<L, G>, 2 * kRing> ring_{};
  std::array<std::array<L, G>, Orders> state_{};
  std::array<std::array<L, G>, kCompensated ? Orders : 1> compensation_{};  // single precision only
  long count_ = 0;
  int now_ = 0;  // ring slot of the current interval end
};

/// I^r(Delta^p f) / tau^(r+p) from the time-scaled integrals J_k = I^k f / tau^k (J[0] = f):
/// the identity in the file comment, for p = 0, 1, 2. Needs J up to index r + p.
/// @realtime no allocation, no throw
template <class Scalar>
inline Scalar scaled_moment(const Scalar* J, int p, int r) noexcept {
  const Scalar rr = static_cast<Scalar>(r);
  switch (p) {
    case 0: return J[r];
    case 1: return J[r] - rr * J[r + 1];
    default: return J[r] - Scalar(2) * rr * J[r + 1] + rr * (rr + Scalar(1)) * J[r + 2];
  }
}

}  // namespace algid
