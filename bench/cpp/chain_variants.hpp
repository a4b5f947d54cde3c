#pragma once
// Experimental variants of algid::IntegratorChain, for the float diagnosis in
// float_accuracy.cpp only (not part of the library). Same algorithm and interface as
// cpp/include/algid/integrator_chain.hpp; what changes is the precision of the running state:
//
//   Accum = double, kKahan = false: samples, ring and quadrature weights in Scalar (float),
//                                  the 5 x 3 state of iterated integrals (and its propagation)
//                                  in double; read out rounded to Scalar.
//   Accum = Scalar, kKahan = true:  everything in float, the state update
//                                  I^r += [sum_{q<r} h^(r-q)/(r-q)! I^q + increment]
//                                  done with Kahan compensated summation (one float of
//                                  compensation per state entry, 4 extra flops per entry).
#include <algid/quadrature.hpp>
#include <algid/types.hpp>

namespace algid_bench {

template <int P, class Scalar, class Accum, bool kKahan>
class VariantChain {
 public:
  static constexpr int kOrders = 5;
  static constexpr int kPowers = 3;
  using Input = Scalar;

  /// Weights in Scalar, propagation in Accum.
  struct Rule {
    explicit Rule(double h) : weights(static_cast<Scalar>(h)), propagate(static_cast<Accum>(h)) {}
    algid::InterpolatoryRule<P, kOrders, Scalar> weights;
    algid::InterpolatoryRule<P, kOrders, Accum> propagate;
  };

  void reset() noexcept {
    count_ = 0;
    state_.setZero();
    comp_.setZero();
    value_.setZero();
  }

  bool push(Scalar f, Scalar delta, const Rule& rule) noexcept {
    const int slot = static_cast<int>(count_ % kRing);
    const Scalar g[kPowers] = {f, delta * f, delta * delta * f};
    for (int p = 0; p < kPowers; ++p) {
      ring_(slot, p) = g[p];
      ring_(slot + kRing, p) = g[p];
    }
    ++count_;
    if (count_ < P) return false;
    const long j = count_ - P;
    const long start = j - (P / 2 - 1) > 0 ? j - (P / 2 - 1) : 0;
    const int off = static_cast<int>(j - start);
    const int first = static_cast<int>(start % kRing);
    increment_.noalias() = rule.weights.weights(off) * ring_.template block<P, kPowers>(first, 0);
    const auto& prop = rule.propagate.propagate();
    if constexpr (!kKahan) {
      algid::Matrix<Accum, kOrders, kPowers> next;
      next.noalias() = prop * state_;
      state_ = next + increment_.template cast<Accum>();
    } else {
      // New I^r from the old I^1..I^r: compute from the highest order down so that the lower
      // orders are still the old ones.
      for (int p = 0; p < kPowers; ++p) {
        for (int r = kOrders - 1; r >= 0; --r) {
          Accum small = increment_(r, p);
          for (int q = 0; q < r; ++q) small += prop(r, q) * state_(q, p);
          const Accum y = small - comp_(r, p);
          const Accum t = state_(r, p) + y;
          comp_(r, p) = (t - state_(r, p)) - y;
          state_(r, p) = t;
        }
      }
    }
    const int end = static_cast<int>((j + 1) % kRing);
    value_ = ring_.row(end).transpose();
    return true;
  }

  Scalar operator()(int p, int r) const noexcept {
    return r == 0 ? value_(p) : static_cast<Scalar>(state_(r - 1, p));
  }

 private:
  static constexpr int kRing = 2 * P;
  algid::Matrix<Scalar, 2 * kRing, kPowers> ring_ = algid::Matrix<Scalar, 2 * kRing, kPowers>::Zero();
  algid::Matrix<Accum, kOrders, kPowers> state_ = algid::Matrix<Accum, kOrders, kPowers>::Zero();
  algid::Matrix<Accum, kOrders, kPowers> comp_ = algid::Matrix<Accum, kOrders, kPowers>::Zero();
  algid::Matrix<Scalar, kOrders, kPowers> increment_ = algid::Matrix<Scalar, kOrders, kPowers>::Zero();
  algid::Vector<Scalar, kPowers> value_ = algid::Vector<Scalar, kPowers>::Zero();
  long count_ = 0;
};

}  // namespace algid_bench
