#pragma once
/// @file lane_chain.hpp
/// ChainEstimator's layout for chains of three DOF or more (see chain_estimator.hpp for the
/// interface): every DOF of the chain side by side, one per SIMD lane, for every step of
/// every sample. DOF i sits in lane i % W of register i / W (W = lane_width(): 2 doubles with
/// SSE2, 4 with AVX2, 4 or 8 with AVX-512), and so do its acceleration and force.
///
/// Per sample:
///   1. the integrator chains of all accelerations and all forces advance, W signals per
///      register operation (IntegratorLanes);
///   2. each signal's rows of eq. 5 are formed from its time-scaled integrals (the recurrence
///      R(q, s) of dof_estimator.hpp); a DOF's spring columns subtract the rows of its
///      neighbours, which are the same registers moved one lane (LaneOps::from_previous /
///      from_next), with zero lanes beyond the walls;
///   3. the 4x4 systems of W DOF are solved at once by Cramer's rule (cramer_lanes4()), their
///      equilibrated Hadamard ratios computed (equilibrated_hadamard2()), the validity rule
///      applied lane by lane, and eq. 7 advanced (RatioLanes);
///   4. the estimates are formed in the lanes they are read from (mass(), damping(),
///      stiffness() view them in place) and the interior springs fused.
/// A DOF with a 3x3 system (a free right end) is embedded as the 4x4 system with row and
/// column 4 of the identity, which has the same determinant, the same first three Cramer
/// numerators and the same equilibrated Hadamard ratio; its lane of eq. 7 decays with the 3x3
/// exponent. Lanes beyond the last DOF carry zero signals and are never valid.
///
/// There is no separate batch path: run() is update() sample by sample, which is already
/// vectorised across the DOF.

#include "algid/chain_config.hpp"
#include "algid/cramer.hpp"
#include "algid/detail/chain_common.hpp"
#include "algid/detail/lanes.hpp"
#include "algid/dof_estimator.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/quadrature.hpp"
#include "algid/ratio_estimator.hpp"
#include "algid/types.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace algid {
namespace detail {

/// ChainEstimator<N, Scalar, P> for N >= 3 (any N works; smaller chains use PerDofChain).
template <int N, class Scalar, int P>
class LaneChain : public ChainCommon<LaneChain<N, Scalar, P>, N, Scalar, P> {
  static_assert(N >= 1, "a chain has at least one DOF");
  using Common = ChainCommon<LaneChain<N, Scalar, P>, N, Scalar, P>;
  using Common::config_;
  using Common::finite;
  using Common::free_end;
  using Common::is_reduced;
  using Common::reduced_last;

 public:
  /// Lanes per register (DOF side by side).
  static constexpr int kLanes = lane_width<N, Scalar>();
  /// Registers of DOF (and of signals); the springs k_1 .. k_{N+1} take kSpringRegisters.
  static constexpr int kRegisters = (N + kLanes - 1) / kLanes;
  static constexpr int kSpringRegisters = (N + 1 + kLanes - 1) / kLanes;
  using L = Lanes<Scalar, kLanes>;
  using Ops = LaneOps<Scalar, kLanes>;
  static_assert(sizeof(L) == kLanes * sizeof(Scalar), "registers of lanes are contiguous: mass() views them");
  /// Integrals of the accelerations (J_0 .. J_7 needed) and of the forces (J_0 .. J_5).
  using AccelChain = IntegratorLanes<P, kAccelOrders, Scalar, kLanes, kRegisters>;
  using ForceChain = IntegratorLanes<P, kForceOrders, Scalar, kLanes, kRegisters>;
  /// The quadrature rule both are advanced with.
  using Rule = InterpolatoryRule<P, kAccelOrders, Scalar>;
  using Config = ChainConfig<Scalar>;
  using Common::update;
  static_assert(Common::kDelay == Rule::kDelay, "the quadrature's delay");

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit LaneChain(const Config& config) : Common(config) {
    Rule rule;
    rule.configure(config.dt);
    weights_.configure(rule);
    reduced_.setZero();
    if (reduced_last()) reduced_((N - 1) % kLanes) = Scalar(1);
    reseed();
  }

  /// Restart at a new t0: the next sample is the first of a new window.
  /// @realtime no allocation, no throw
  void reseed() noexcept {
    accel_.reset();
    force_.reset();
    const L nan = L::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    for (auto& r : ratio_) r.reset();
    det_.fill(L::Zero());
    weight_.fill(L::Zero());
    hadamard2_num_.fill(L::Zero());
    hadamard2_den_.fill(L::Ones());
    for (auto& v : numerator_) v.fill(L::Zero());
    for (auto& v : estimate_) v.fill(nan);
    spring_.fill(nan);
    if (free_end()) spring_[N / kLanes](N % kLanes) = Scalar(0);
    valid_.fill(false);
  }

  /// Consume one simultaneous sample of the accelerations [m/s^2] and forces [N].
  /// @realtime no allocation, no throw, O(N)
  ALGID_FLATTEN Status update(const Scalar* accel, const Scalar* force) noexcept {
    if (!finite(accel, force)) {
      reseed();
      return Status::kBadInput;
    }
    const bool advanced = accel_.push(accel, N, weights_);
    force_.push(force, N, weights_);
    if (!advanced) return Status::kWarmup;

    // What every DOF shares at this interval end.
    const long samples = accel_.count();
    const Scalar intervals = static_cast<Scalar>(samples - P);
    const Scalar prev_tau = intervals * config_.dt;
    const Scalar tau = (intervals + Scalar(1)) * config_.dt;
    const Scalar inv_tau = Scalar(1) / tau;
    Scalar inv_pow[kAccelOrders + 1];
    inv_pow[0] = Scalar(1);
    for (int r = 1; r <= kAccelOrders; ++r) inv_pow[r] = inv_pow[r - 1] * inv_tau;
    const Scalar decay4 = RatioEstimator<4, Scalar>::decay(prev_tau, tau);
    const Scalar decay3 = reduced_last() ? RatioEstimator<3, Scalar>::decay(prev_tau, tau) : decay4;
    const L samples_now = L::Constant(static_cast<Scalar>(samples));

    // The rows of every signal: acceleration columns 0, 1 (mass, damping), the spring column
    // with a zero register before and after (the walls' lanes), force rows.
    L rows[2][4][kRegisters], spring[4][kRegisters + 2], force_rows[4][kRegisters];
    for (int q = 0; q < 4; ++q) {
      spring[q][0].setZero();
      spring[q][kRegisters + 1].setZero();
    }
    for (int g = 0; g < kRegisters; ++g) {
      L J[kAccelOrders + 1];
      accel_.scaled(g, inv_pow, J);
      for (int q = 0; q < 4; ++q) {
        rows[0][q][g] = row(J, q, q);
        rows[1][q][g] = row(J, q, q + 1);
        spring[q][g + 1] = row(J, q, q + 2);
      }
      L F[kForceOrders + 1];
      force_.scaled(g, inv_pow, F);
      for (int q = 0; q < 4; ++q) force_rows[q][g] = row(F, q, q);
    }

    const L zero = L::Zero(), one = L::Ones();
    const L nan = L::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    const Scalar inv_tau2 = inv_tau * inv_tau;
    for (int g = 0; g < kRegisters; ++g) {
      // Eq. 5 of the DOF of register g (column-major S, s): springs k_i, k_{i+1} against the
      // neighbours' rows one lane away.
      L S[16], s[4];
      for (int q = 0; q < 4; ++q) {
        const L& self = spring[q][g + 1];
        S[0 * 4 + q] = rows[0][q][g];
        S[1 * 4 + q] = rows[1][q][g];
        S[2 * 4 + q] = self - Ops::from_previous(self, spring[q][g]);
        S[3 * 4 + q] = self - Ops::from_next(self, spring[q][g + 2]);
        s[q] = force_rows[q][g];
      }
      const bool has_reduced = reduced_last() && g == (N - 1) / kLanes;
      if (has_reduced) {  // the 3x3 DOF: row and column 4 of the identity
        for (int q = 0; q < 3; ++q) {
          S[3 * 4 + q] = Ops::if_less(zero, reduced_, zero, S[3 * 4 + q]);
          S[q * 4 + 3] = Ops::if_less(zero, reduced_, zero, S[q * 4 + 3]);
        }
        S[15] = Ops::if_less(zero, reduced_, one, S[15]);
        s[3] = Ops::if_less(zero, reduced_, zero, s[3]);
      }
      L det, numerator[4], h2num, h2den;
      cramer_lanes4(S, s, det, numerator);
      equilibrated_hadamard2<4>(S, det, h2num, h2den);
      // Numerators of the physical parameters (tau scaling undone, see dof_estimator.hpp).
      const L scaled[4] = {numerator[0], numerator[1] * inv_tau, numerator[2] * inv_tau2, numerator[3] * inv_tau2};
      L weight, weighted[4];
      weigh_lanes<4>(det, scaled, h2num, h2den, samples_now, config_.validity, weight, weighted);
      const L rho = has_reduced ? Ops::if_less(zero, reduced_, L::Constant(decay3), L::Constant(decay4))
                                : L::Constant(decay4);
      RatioLanes<Scalar, kLanes>& ratio = ratio_[static_cast<std::size_t>(g)];
      ratio.add(rho, Scalar(0.5) * config_.dt, weight, weighted);
      // Eq. 7 estimates where valid (NaN elsewhere), in the lanes the accessors read.
      L estimate[4];
      estimates_lanes<4>(ratio.denominator(), ratio.numerators(), estimate);
      for (int j = 0; j < 4; ++j) estimate_[j][g] = estimate[j];
      if (has_reduced) estimate_[3][g] = Ops::if_less(zero, reduced_, nan, estimate_[3][g]);
      det_[g] = det;
      weight_[g] = weight;
      hadamard2_num_[g] = h2num;
      hadamard2_den_[g] = h2den;
      for (int j = 0; j < 4; ++j) numerator_[j][g] = scaled[j];
    }
    collect();
    return Status::kOk;
  }

  /// Consume a record of T samples (T x N, row-major) and call `observe(t, status)` after each:
  /// update() sample by sample (the lanes already hold the DOF side by side). Returns 0, the
  /// number of samples that went through instant blocks (see PerDofChain::run()).
  /// @realtime no allocation; no throw unless `observe` throws
  template <class Observer>
  long run(const Scalar* accel, const Scalar* force, long T, Observer&& observe) {
    for (long t = 0; t < T; ++t) observe(t, update(accel + t * N, force + t * N));
    return 0;
  }

  /// Eq. 7 estimates of the masses m_i [kg] (NaN where not valid), viewed in place.
  Eigen::Map<const Vector<Scalar, N>> mass() const noexcept {
    return Eigen::Map<const Vector<Scalar, N>>(estimate_[0][0].data());
  }
  /// Eq. 7 estimates of the dampings c_i [N s/m].
  Eigen::Map<const Vector<Scalar, N>> damping() const noexcept {
    return Eigen::Map<const Vector<Scalar, N>>(estimate_[1][0].data());
  }
  /// Fused eq. 7 estimates of the springs k_1 .. k_{n+1} [N/m] (see ChainEstimator).
  Eigen::Map<const Vector<Scalar, N + 1>> stiffness() const noexcept {
    return Eigen::Map<const Vector<Scalar, N + 1>>(spring_[0].data());
  }
  /// Per-DOF validity of the eq. 7 estimates.
  const std::array<bool, N>& valid() const noexcept { return valid_; }

  /// Eq. 7 estimate [m_i, c_i, k_i, k_{i+1}] of DOF i (0-based); NaN while not valid, and in
  /// slot 3 of a 3x3 DOF.
  Vector<Scalar, 4> theta(int i) const noexcept {
    Vector<Scalar, 4> out;
    for (int j = 0; j < 4; ++j) out(j) = lane(estimate_[j], i);
    return out;
  }
  /// Instantaneous Cramer solution of eq. 5 for DOF i (0-based), same layout as theta().
  Vector<Scalar, 4> theta_instant(int i) const noexcept {
    const Scalar det = lane(det_, i);
    Vector<Scalar, 4> out = Vector<Scalar, 4>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    if (!(std::isfinite(det) && det != Scalar(0))) return out;
    const int m = is_reduced(i) ? 3 : 4;
    for (int j = 0; j < m; ++j) out(j) = lane(numerator_[j], i) * (Scalar(1) / det);
    return out;
  }
  /// Equilibrated Hadamard ratio of DOF i's last system, in [0, 1].
  Scalar hadamard(int i) const noexcept {
    const Scalar h2 = lane(hadamard2_num_, i) / lane(hadamard2_den_, i);
    return std::isfinite(h2) && h2 > Scalar(0) ? std::sqrt(h2) : Scalar(0);
  }
  /// Whether DOF i's last instantaneous solution was trusted.
  bool instant_valid(int i) const noexcept { return lane(weight_, i) > Scalar(0); }
  /// Samples consumed since t0.
  long samples() const noexcept { return accel_.count(); }

 private:

  template <std::size_t R>
  static Scalar lane(const std::array<L, R>& registers, int i) noexcept {
    return registers[static_cast<std::size_t>(i / kLanes)](i % kLanes);
  }

  // R(q, s) = J_s - kRowA[q] J_(s+1) + kRowB[q] J_(s+2) (dof_estimator.hpp), lane by lane.
  static L row(const L* J, int q, int s) noexcept {
    return Ops::madd(L::Constant(static_cast<Scalar>(kRowB[q])), J[s + 2],
                     Ops::madd(L::Constant(static_cast<Scalar>(-kRowA[q])), J[s + 1], J[s]));
  }

  // The fused springs and the validity flags from the eq. 7 estimates of every lane: k_i is
  // the mean of DOF i's estimate (slot 2) and DOF i-1's (slot 3) where both are valid, else the
  // valid one; k_{N+1} = 0 at a free end.
  void collect() noexcept {
    const L zero = L::Zero();
    const L nan = L::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    for (int g = 0; g < kSpringRegisters; ++g) {
      const bool dof = g < kRegisters;
      const L own = dof ? estimate_[2][g] : nan;
      const L left = Ops::from_previous(dof ? estimate_[3][g] : nan, g > 0 ? estimate_[3][g - 1] : nan);
      const L fused = Ops::if_equal(left, left, Scalar(0.5) * (own + left), own);
      spring_[g] = dof ? Ops::if_less(zero, ratio_[static_cast<std::size_t>(g)].denominator(), fused, left) : left;
    }
    if (free_end()) spring_[N / kLanes](N % kLanes) = Scalar(0);
    for (int i = 0; i < N; ++i) {
      valid_[static_cast<std::size_t>(i)] = ratio_[static_cast<std::size_t>(i / kLanes)].denominator()(i % kLanes) > Scalar(0);
    }
  }

  LaneWeights<P, kAccelOrders, Scalar, kLanes> weights_;
  AccelChain accel_{};
  ForceChain force_{};
  L reduced_ = L::Zero();  // 1 in the lane of a 3x3 DOF, in the last register of DOF
  std::array<RatioLanes<Scalar, kLanes>, kRegisters> ratio_{};
  // The last sample's solution, lane by lane: det S, the eq. 7 weight (> 0: trusted), the
  // squared Hadamard ratio as num / den, the tau-unscaled Cramer numerators.
  std::array<L, kRegisters> det_{}, weight_{}, hadamard2_num_{}, hadamard2_den_{};
  std::array<std::array<L, kRegisters>, 4> numerator_{};
  // Eq. 7 estimates (slot j of every DOF), and the fused springs, read in place.
  std::array<std::array<L, kSpringRegisters>, 4> estimate_{};
  std::array<L, kSpringRegisters> spring_{};
  std::array<bool, N> valid_{};
};

}  // namespace detail
}  // namespace algid
