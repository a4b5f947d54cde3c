#pragma once
/// @file integrator_chain.hpp
/// The iterated integrator chains of eq. 6 of a chain's measured signals, side by side in SIMD
/// lanes, and the identity that turns them into every integral eqs. 4-6 need.
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
#include "algid/detail/storage.hpp"
#include "algid/quadrature.hpp"
#include "algid/types.hpp"

namespace algid {
namespace detail {

/// state += step, Kahan-compensated (`compensation` carries the lost low-order part) when
/// Compensated.
template <bool Compensated, class T>
inline void accumulate(T& state, T& compensation, const T& step) noexcept {
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

/// Iterated integrals I^1 .. I^Orders of up to G W signals that share one clock (a chain's
/// accelerations, or its forces), one signal per SIMD lane: signal k in lane k % W of register
/// k / W, so that one register operation advances W signals. Each lane follows the recurrence
/// of quadrature.hpp with the same rule; the sums are formed with fused multiply-adds where the
/// build has them. Lanes beyond the signals pushed stay zero.
/// Storage: a doubled ring of 2P samples per register (any stencil is a contiguous block), the
/// Orders states per register and, in single precision, their Kahan compensation; allocated
/// once by configure() when G is Dynamic. Do not build with -ffast-math.
/// @tparam P interpolation points of the quadrature.
/// @tparam Orders highest order of iterated integral kept.
/// @tparam W lanes per register; G registers (or Dynamic).
template <int P, int Orders, class Scalar, int W, int G>
class IntegratorLanes {
  static_assert(Orders >= 1, "at least one integral");
  static_assert(W >= 1 && (G >= 1 || G == Dynamic), "at least one lane");

 public:
  using L = detail::Lanes<Scalar, W>;
  /// Highest order of iterated integral kept.
  static constexpr int kOrders = Orders;
  /// Kahan-compensated state update in single precision: the state grows like tau^r while
  /// each step adds a small amount, which is where single precision loses its digits.
  static constexpr bool kCompensated = sizeof(Scalar) < sizeof(double);

  /// Size the storage for `registers` registers (G, or any number when G is Dynamic) and
  /// reset. May be called in the configuration phase only.
  void configure(int registers) {
    registers_ = detail::fixed_or<G>(registers);
    ring_.resize(2 * kRing * registers_);
    state_.resize(Orders * registers_);
    compensation_.resize((kCompensated ? Orders : 1) * registers_);
    reset();
  }

  /// Forget everything: the next sample is t_0. @realtime no allocation, no throw.
  void reset() noexcept {
    count_ = 0;
    now_ = 0;
    ring_.fill(L::Zero());
    state_.fill(L::Zero());
    compensation_.fill(L::Zero());
  }

  /// Consume the simultaneous samples f[0 .. n-1] (n <= registers W) of the signals in lanes
  /// 0 .. n-1. Returns true when the integrals have advanced to a new interval end (from the
  /// P-th sample on). @realtime no allocation, no throw.
  template <int RuleOrders>
  bool push(const Scalar* f, int n, const LaneWeights<P, RuleOrders, Scalar, W>& rule) noexcept {
    static_assert(RuleOrders >= Orders, "the rule must cover every order of the chain");
    const int R = registers();
    const int slot = static_cast<int>(count_ % kRing);
    L* copy0 = &ring_[slot * R];
    L* copy1 = &ring_[(slot + kRing) * R];
    for (int k = 0; k < n; ++k) {
      copy0[k / W](k % W) = f[k];
      copy1[k / W](k % W) = f[k];
    }
    ++count_;
    if (count_ < P) return false;
    const long j = count_ - P;  // interval [t_j, t_{j+1}]
    const long start = InterpolatoryRule<P, Orders, Scalar>::stencil_start(j);
    const int off = static_cast<int>(j - start);
    const L* stencil = &ring_[static_cast<int>(start % kRing) * R];
    now_ = static_cast<int>((j + 1) % kRing);
    using Ops = detail::LaneOps<Scalar, W>;
    for (int g = 0; g < R; ++g) {
      // Every order from the old lower orders: the step is computed whole before the state moves.
      L step[Orders];
      detail::static_for<0, Orders>([&](auto order) {
        constexpr int r = decltype(order)::value;  // unrolled: the carry below has r terms
        L acc = stencil[g] * rule.weight(off, r, 0);
        for (int m = 1; m < P; ++m) acc = Ops::madd(stencil[m * R + g], rule.weight(off, r, m), acc);
        for (int q = 0; q < r; ++q) acc = Ops::madd(state_[q * R + g], rule.carry(r, q), acc);
        step[r] = acc;
      });
      for (int r = 0; r < Orders; ++r)
        detail::accumulate<kCompensated>(state_[r * R + g], compensation_[(kCompensated ? r : 0) * R + g], step[r]);
    }
    return true;
  }

  /// Time-scaled integrals J_r = I^r f / tau^r, r = 0 .. Orders, of the signals of register g
  /// at the current interval end, given inv_tau_pow[r] = tau^-r (J_0 is the sample itself).
  /// @realtime no allocation, no throw.
  void scaled(int g, const Scalar* inv_tau_pow, L* J) const noexcept {
    const int R = registers();
    J[0] = ring_[now_ * R + g];
    for (int r = 1; r <= Orders; ++r) J[r] = inv_tau_pow[r] * state_[(r - 1) * R + g];
  }

  /// I^r of the signal in lane k (r = 0: the sample) at the current interval end.
  Scalar integral(int r, int k) const noexcept {
    const int R = registers();
    const L& x = r == 0 ? ring_[now_ * R + k / W] : state_[(r - 1) * R + k / W];
    return x(k % W);
  }

  /// Samples consumed since the last reset.
  long count() const noexcept { return count_; }
  /// Registers of signals.
  int registers() const noexcept { return G == Dynamic ? registers_ : G; }

 private:
  static constexpr int kRing = 2 * P;  // >= 3P/2 - 1 samples: a centred stencil's span
  // Register g of ring slot s at [s * registers_ + g] (slots doubled: s < 2 kRing), of order r
  // at [(r - 1) * registers_ + g].
  detail::Storage<L, G == Dynamic ? Dynamic : 2 * kRing * G> ring_;
  detail::Storage<L, G == Dynamic ? Dynamic : Orders * G> state_;
  detail::Storage<L, G == Dynamic ? Dynamic : (kCompensated ? Orders : 1) * G> compensation_;  // single precision only
  int registers_ = G == Dynamic ? 0 : G;  // read through registers(): a constant when G is fixed
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
