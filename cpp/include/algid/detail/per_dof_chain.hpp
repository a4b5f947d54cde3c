#pragma once
/// @file per_dof_chain.hpp
/// ChainEstimator's layout for chains of one or two DOF (see chain_estimator.hpp for the
/// interface): one DofEstimator per DOF, the integrator chains vectorised across their orders
/// (IntegratorChain), and a batch path, run() and record(), that solves the eq. 5 systems of
/// kBlock consecutive instants side by side, one instant per SIMD lane, to the bit as update()
/// would.

#include "algid/chain_config.hpp"
#include "algid/detail/chain_common.hpp"
#include "algid/detail/lanes.hpp"
#include "algid/cramer.hpp"
#include "algid/dof_estimator.hpp"
#include "algid/histories.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/ratio_estimator.hpp"
#include "algid/types.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace algid {
namespace detail {

/// ChainEstimator<N, Scalar, P> for N = 1, 2 (any N works; larger chains use LaneChain).
template <int N, class Scalar, int P>
class PerDofChain : public ChainCommon<PerDofChain<N, Scalar, P>, N, Scalar, P> {
  using Common = ChainCommon<PerDofChain<N, Scalar, P>, N, Scalar, P>;
  using Common::config_;
  using Common::finite;
  using Common::free_end;
  using Common::is_reduced;
  using Common::reduced_last;

  static_assert(N >= 1, "a chain has at least one DOF");

 public:
  /// Rows of the largest system of eq. 5 solved: a chain of one DOF only has the 3x3 system of
  /// k_1 + k_2 (or of a free end), whose rows need one order less of each signal.
  static constexpr int kSystemRows = N == 1 ? 3 : 4;
  /// Integrator chains of the N accelerations (orders 1..7 needed, 8 kept) and of the N forces
  /// (1..5 needed, 1..4 for one DOF; kForceKept kept): the extra orders pad to whole SIMD
  /// registers (6 with SSE2, 8 with AVX; 4 for one DOF), which costs less than the partial
  /// registers they replace.
  static constexpr int kForceKept = simd_padded<Scalar>(kForceOrders - (4 - kSystemRows), kAccelOrders + 1);
  using AccelChain = IntegratorChain<P, kAccelOrders + 1, Scalar, N>;
  using ForceChain = IntegratorChain<P, kForceKept, Scalar, N>;
  /// The quadrature rule both are advanced with.
  using Rule = typename AccelChain::Rule;
  using Config = ChainConfig<Scalar>;
  using Common::update;
  static_assert(Common::kDelay == Rule::kDelay, "the quadrature's delay");

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit PerDofChain(const Config& config) : Common(config) {
    rule_.configure(config.dt);
    reseed();
  }

  /// Restart at a new t0: the next sample is the first of a new window.
  /// @realtime no allocation, no throw
  void reseed() noexcept {
    accel_.reset();
    force_.reset();
    for (auto& d : full_) d.reset();
    last_.reset();
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    mass_.setConstant(nan);
    damping_.setConstant(nan);
    stiffness_.setConstant(nan);
    if (free_end()) stiffness_(N) = Scalar(0);
    valid_.fill(false);
    samples_ = 0;
  }

  /// Consume one simultaneous sample of the accelerations [m/s^2] and forces [N].
  /// @realtime no allocation, no throw, O(N)
  ALGID_FLATTEN Status update(const Scalar* accel, const Scalar* force) noexcept {
    if (!finite(accel, force)) {
      reseed();
      return Status::kBadInput;
    }
    ++samples_;
    const bool advanced = accel_.push(accel, rule_);
    force_.push(force, rule_);
    if (!advanced) return Status::kWarmup;
    const Instant<Scalar> now = instant(samples_);
    Vector<Scalar, AccelChain::kOrders + 1> inv_pow;
    inv_pow(0) = Scalar(1);
    for (int r = 1; r <= AccelChain::kOrders; ++r) inv_pow(r) = inv_pow(r - 1) * now.inv_tau;
    // Each signal's rows once: an acceleration enters its own DOF and both neighbours'.
    accel_.scaled(inv_pow, accel_scaled_);
    force_.scaled(inv_pow, force_scaled_);
    for (int i = 0; i < N; ++i) {
      signal_rows<3, kSystemRows>(accel_scaled_.col(i).data(), accel_rows_[i]);
      signal_rows<1, kSystemRows>(force_scaled_.col(i).data(), force_rows_[i]);
    }
    for (int i = 0; i < N; ++i) {
      const auto* left = i > 0 ? &accel_rows_[i - 1] : nullptr;
      const auto* right = i + 1 < N ? &accel_rows_[i + 1] : nullptr;
      if (is_reduced(i)) {
        last_.update(left, accel_rows_[i], right, force_rows_[i], now, config_.validity);
      } else {
        full_[i].update(left, accel_rows_[i], right, force_rows_[i], now, config_.validity);
      }
    }
    collect();
    return Status::kOk;
  }

  /// Samples per block of run(): the eq. 5 systems of kBlock consecutive instants are solved
  /// side by side, one per SIMD lane (8 fills an AVX-512 register of doubles, two of AVX2,
  /// four of SSE2).
  static constexpr int kBlock = 8;

  /// Consume a record of T simultaneous samples (`accel`, `force`: T x N, row-major: sample t
  /// at accel + t N) and call `observe(t, status)` after each sample t, with the estimator in exactly
  /// the state a call of update() would have left it in: every estimate, flag and accessor,
  /// to the bit. Stretches of kBlock finite samples after the warm-up go through as a block:
  /// the chains and eq. 7 still advance sample by sample (the chains with their weights held
  /// in registers for the block), but the rows, the systems of eq. 5, Cramer's rule, the
  /// Hadamard ratio and the validity rule are computed for the kBlock instants at once, lane
  /// by lane with the operations of update() (cramer_lanes(), equilibrated_hadamard2(),
  /// weigh_lanes()). That is the batch path; firmware calls update().
  /// Scratch is on the stack: about 35 kBlock N scalars (4.5 KiB for N = 2 in double).
  /// Returns how many of the T samples went through blocks.
  /// @realtime no allocation; no throw unless `observe` throws
  template <class Observer>
  ALGID_FLATTEN long run(const Scalar* accel, const Scalar* force, long T, Observer&& observe) {
    return drive(
        accel, force, T,
        [&](const BlockSolution& solution, long t) {
          for (int b = 0; b < kBlock; ++b) {
            commit(solution, b);
            observe(t + b, Status::kOk);
          }
        },
        [&](long t, Status s) { observe(t, s); });
  }

  /// ChainCommon::record() (the histories of a record; what the Python `run()` returns) through
  /// the block path, with eq. 7's estimates at a block's instants formed side by side as well
  /// (one reciprocal per DOF and block rather than per sample) and written straight into `out`
  /// (write_block()). Between the blocks' last instants nothing reads the per-sample state, so
  /// only eq. 7 advances there. The same bits as run() with an observer that copies the
  /// accessors; the estimator is left as update() would leave it. Scratch: run()'s, plus
  /// 8 kBlock N scalars (eq. 7's integrals of a block).
  /// @realtime no allocation, no throw
  ALGID_FLATTEN long record(const Scalar* accel, const Scalar* force, long T, const Histories<Scalar>& out) noexcept {
    return drive(
        accel, force, T, [&](const BlockSolution& solution, long t) { commit_block(solution, t, out); },
        [&](long t, Status s) { this->write_row(t, s, out); });
  }

  /// Eq. 7 estimates of the masses m_i [kg] (NaN where not valid).
  Eigen::Map<const Vector<Scalar, N>> mass() const noexcept { return Eigen::Map<const Vector<Scalar, N>>(mass_.data()); }
  /// Eq. 7 estimates of the dampings c_i [N s/m].
  Eigen::Map<const Vector<Scalar, N>> damping() const noexcept {
    return Eigen::Map<const Vector<Scalar, N>>(damping_.data());
  }
  /// Fused eq. 7 estimates of the springs k_1 .. k_{n+1} [N/m]: an interior spring is the mean
  /// of the estimates of its two DOF (those that are valid). For N = 1 with walls, k_1 holds
  /// the identifiable sum k_1 + k_2 and k_2 is NaN; with a free end k_{n+1} = 0.
  Eigen::Map<const Vector<Scalar, N + 1>> stiffness() const noexcept {
    return Eigen::Map<const Vector<Scalar, N + 1>>(stiffness_.data());
  }
  /// Per-DOF validity of the eq. 7 estimates.
  const std::array<bool, N>& valid() const noexcept { return valid_; }

  /// Eq. 7 estimate [m_i, c_i, k_i, k_{i+1}] of DOF i (0-based); a reduced DOF has NaN in
  /// slot 3 (and k_1 + k_2 in slot 2 when N = 1 with walls); NaN while not valid.
  Vector<Scalar, 4> theta(int i) const noexcept {
    Vector<Scalar, 4> out = Vector<Scalar, 4>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    if (is_reduced(i)) {
      if (last_.valid()) out.template head<3>() = last_.estimates();
    } else if (full_[i].valid()) {
      out = full_[i].estimates();
    }
    return out;
  }
  /// Instantaneous Cramer solution of eq. 5 for DOF i (0-based), same layout as theta().
  Vector<Scalar, 4> theta_instant(int i) const noexcept {
    Vector<Scalar, 4> out = Vector<Scalar, 4>::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    if (is_reduced(i)) {
      out.template head<3>() = last_.instant();
    } else {
      out = full_[i].instant();
    }
    return out;
  }
  /// Equilibrated Hadamard ratio of DOF i's last system.
  Scalar hadamard(int i) const noexcept { return is_reduced(i) ? last_.hadamard() : full_[i].hadamard(); }
  /// Whether DOF i's last instantaneous solution was trusted.
  bool instant_valid(int i) const noexcept { return is_reduced(i) ? last_.instant_valid() : full_[i].instant_valid(); }
  /// Samples consumed since t0.
  long samples() const noexcept { return samples_; }

 private:
  // The loop of run() and record(): blocks where they can be taken (solved by solve_block(),
  // then handed to `on_block(solution, t)` to commit instants t .. t + kBlock - 1), update()
  // and `on_sample(t, status)` elsewhere. Returns the number of samples in blocks.
  template <class OnBlock, class OnSample>
  ALGID_FLATTEN long drive(const Scalar* accel, const Scalar* force, long T, OnBlock&& on_block, OnSample&& on_sample) {
    // The next block's chains are pushed before this block's samples are committed to eq. 7:
    // independent work the processor can overlap with the commits. The chains are internal
    // state no accessor reads, so running ahead is invisible to the callbacks.
    BlockInputs inputs;
    BlockSolution solution;
    bool pushed = false;  // inputs already holds the block starting at t
    long t = 0, blocked = 0;
    while (t < T) {
      const Scalar* a = accel + t * N;
      const Scalar* f = force + t * N;
      if (pushed || (samples_ >= P - 1 && T - t >= kBlock && finite(a, f, kBlock * N))) {
        if (!pushed) push_block(a, f, inputs);
        solve_block(inputs, solution);  // inputs is free from here
        const long next = t + kBlock;
        const Scalar* na = accel + next * N;
        const Scalar* nf = force + next * N;
        const bool ahead = T - next >= kBlock && finite(na, nf, kBlock * N);
        if (ahead) push_block(na, nf, inputs);
        on_block(static_cast<const BlockSolution&>(solution), t);
        pushed = ahead;
        t = next;
        blocked += kBlock;
      } else {
        on_sample(t, update(a, f));
        ++t;
      }
    }
    return blocked;
  }

  // What every DOF shares at the interval end after `samples` samples (>= P), once per sample.
  Instant<Scalar> instant(long samples) const noexcept {
    Instant<Scalar> now;
    shared(static_cast<Scalar>(samples - P), now.inv_tau, now.decay4, now.decay3);
    now.h = config_.dt;
    now.samples = samples;
    return now;
  }

  // 1 / tau and the eq. 7 decay factors from the previous interval end, given (samples - P) as
  // a scalar or, for the block path, as lanes of instants (the same operations per lane).
  // A decay factor no DOF uses is left as it is.
  template <class T>
  void shared(const T& intervals, T& inv_tau, T& decay4, T& decay3) const noexcept {
    const T prev_tau = intervals * config_.dt;
    const T tau = (intervals + Scalar(1)) * config_.dt;
    inv_tau = reciprocal(tau);
    if (N > 1) decay4 = RatioEstimator<4, Scalar>::decay(prev_tau, tau);  // DOF 1 is full
    if (reduced_last()) decay3 = RatioEstimator<3, Scalar>::decay(prev_tau, tau);
  }

  using BlockLanes = Eigen::Array<Scalar, kBlock, 1>;
  // The chains after each sample of a block, one contiguous column per sample (as the chains
  // hold them), turned into lanes (lane b = instant b) tile by tile in registers by
  // solve_block() (transpose_to_lanes). The samples themselves (J_0) are few: stored as lanes.
  struct BlockInputs {
    Matrix<Scalar, AccelChain::kOrders * N, kBlock> astate;
    Matrix<Scalar, ForceChain::kOrders * N, kBlock> fstate;
    Matrix<Scalar, N, kBlock> avalue, fvalue;
  };
  // Eq. 5 of every DOF solved at the kBlock instants of a block, one per lane, and what the
  // DOFs share at each instant: what commit() feeds to eq. 7 sample by sample.
  // `scaled`: the Cramer numerators scaled to the physical parameters; `h2num`: 0 where not
  // finite; `fed`: column b is what eq. 7 is fed at instant b (DofEstimator::Packed, in the
  // first 4 rows for a 3x3 system).
  struct BlockSolution {
    BlockLanes det[N], scaled[4 * N], h2num[N], h2den[N], decay4, decay3;
    Matrix<Scalar, 8, kBlock> fed[N];
  };

  // Push kBlock finite samples past the warm-up (the chains advance at each) and keep the
  // chains' states after each in `in`: with the weights in registers once the stencils are
  // centred (IntegratorChain::push_steady()), the same bits as push() sample by sample.
  ALGID_FLATTEN void push_block(const Scalar* accel, const Scalar* force, BlockInputs& in) noexcept {
    if (accel_.steady()) {
      if constexpr (std::is_same_v<AccelChain, ForceChain>) {  // both recurrences interleaved
        AccelChain::template push_steady<kBlock, 2>({&accel_, &force_}, {accel, force}, N, rule_,
                                                    {in.astate.data(), in.fstate.data()},
                                                    {in.avalue.data(), in.fvalue.data()});
      } else {
        AccelChain::template push_steady<kBlock, 1>({&accel_}, {accel}, N, rule_, {in.astate.data()}, {in.avalue.data()});
        ForceChain::template push_steady<kBlock, 1>({&force_}, {force}, N, rule_, {in.fstate.data()}, {in.fvalue.data()});
      }
    } else {
      for (int b = 0; b < kBlock; ++b) push_into(accel + b * N, force + b * N, b, in);
    }
  }

  // Push one finite sample past the warm-up (the chains advance) and keep the chains' state as
  // instant b of `in`.
  void push_into(const Scalar* accel, const Scalar* force, int b, BlockInputs& in) noexcept {
    constexpr int kAO = AccelChain::kOrders, kFO = ForceChain::kOrders;
    accel_.push(accel, rule_);
    force_.push(force, rule_);
    in.astate.col(b) = Eigen::Map<const Vector<Scalar, kAO * N>>(accel_.state().data());
    in.fstate.col(b) = Eigen::Map<const Vector<Scalar, kFO * N>>(force_.state().data());
    in.avalue.col(b) = accel_.value();
    in.fvalue.col(b) = force_.value();
  }

  // The rows, eq. 5, Cramer's rule and the Hadamard ratio at the kBlock instants of `in`, which
  // follow the samples_ samples already committed: see run().
  ALGID_FLATTEN void solve_block(const BlockInputs& in, BlockSolution& out) noexcept {
    using Lanes = BlockLanes;
    // What the rows need: J_0 .. J_7 of an acceleration and J_0 .. J_5 of a force (one order
    // less of each for 3x3 systems only).
    constexpr int kA = kAccelOrders + 1 - (4 - kSystemRows);
    constexpr int kF = kForceOrders + 1 - (4 - kSystemRows);
    constexpr int kAO = AccelChain::kOrders, kFO = ForceChain::kOrders;
    static_assert(kA <= kAO + 1 && kF <= kFO + 1, "the chains keep the orders the rows need");
    // What the DOFs share at each instant (instant()), and the time scaling J_r = I^r tau^-r,
    // lane by lane as in update().
    Lanes intervals, inv_tau, samples;
    for (int b = 0; b < kBlock; ++b) {
      intervals(b) = static_cast<Scalar>(samples_ + 1 + b - P);
      samples(b) = static_cast<Scalar>(samples_ + 1 + b);
    }
    out.decay4.setZero();
    out.decay3.setZero();
    shared(intervals, inv_tau, out.decay4, out.decay3);
    Lanes inv_pow[kA];
    inv_pow[0].setConstant(Scalar(1));
    for (int r = 1; r < kA; ++r) inv_pow[r] = inv_pow[r - 1] * inv_tau;
    // The rows of acceleration ka and force kf at the kBlock instants (k < 0: none), from
    // J_r = I^r tau^-r of those signals; computed where the rows are needed, not kept for all N:
    // the scratch then stays small enough for the L1 cache at large N.
    const auto signal_rows_lanes = [&](int ka, Lanes* arows_k, int kf, Lanes* frows_k) {
      Lanes JA[kAO + 1], JF[kFO + 1];  // J_0 .. J_Orders (the padding orders unused)
      if (ka >= 0) {
        JA[0] = in.avalue.row(ka).transpose();
        transpose_to_lanes<kAO>(in.astate.col(0).data() + ka * kAO, kAO * N, &JA[1]);
      }
      if (kf >= 0) {
        JF[0] = in.fvalue.row(kf).transpose();
        transpose_to_lanes<kFO>(in.fstate.col(0).data() + kf * kFO, kFO * N, &JF[1]);
      }
      for (int r = 1; r < kA; ++r) {
        if (ka >= 0) JA[r] = inv_pow[r] * JA[r];
        if (kf >= 0 && r < kF) JF[r] = inv_pow[r] * JF[r];
      }
      if (ka >= 0) lane_rows<3, kSystemRows>(JA, arows_k);
      if (kf >= 0) lane_rows<1, kSystemRows>(JF, frows_k);
    };
    // Eq. 5 of every DOF for the kBlock instants, one per lane. The rows of the accelerations
    // i - 1, i, i + 1 (4 x 3 column-major each) roll through three slots; force i's rows go
    // with acceleration i + 1's.
    Lanes arows[3][12], frows[4];
    signal_rows_lanes(0, arows[0], N == 1 ? 0 : -1, frows);  // one DOF: its force here too
    for (int i = 0; i < N; ++i) {
      if (N > 1) signal_rows_lanes(i + 1 < N ? i + 1 : -1, arows[(i + 1) % 3], i, frows);
      const Lanes* left = i > 0 ? arows[(i + 2) % 3] : nullptr;
      const Lanes* right = i + 1 < N ? arows[(i + 1) % 3] : nullptr;
      if (is_reduced(i)) {
        solve_lanes<3>(left, arows[i % 3], right, frows, inv_tau, samples, i, out, last_);
      } else {
        solve_lanes<4>(left, arows[i % 3], right, frows, inv_tau, samples, i, out, full_[static_cast<std::size_t>(i)]);
      }
    }
  }

  // Eq. 7 and the outputs for instant b of a solved block: the sample is then consumed.
  void commit(const BlockSolution& in, int b) noexcept {
    for (int i = 0; i < N; ++i) {
      const Vector<Scalar, 4> scaled(in.scaled[4 * i](b), in.scaled[4 * i + 1](b), in.scaled[4 * i + 2](b),
                                     is_reduced(i) ? Scalar(0) : in.scaled[4 * i + 3](b));  // 3x3: 3 numerators
      if (is_reduced(i)) {
        last_.commit_weighed(in.det[i](b), scaled.template head<3>(), in.h2num[i](b), in.h2den[i](b),
                             in.fed[i].col(b).template head<4>(), in.decay3(b), config_.dt);
      } else {
        full_[static_cast<std::size_t>(i)].commit_weighed(in.det[i](b), scaled, in.h2num[i](b), in.h2den[i](b),
                                                          in.fed[i].col(b), in.decay4(b), config_.dt);
      }
    }
    collect();
    ++samples_;
  }

  // Eq. 7's double integrals of every DOF after each instant of a block: column b of
  // integrals[i] holds DOF i's [I^2 |Delta|, I^2 sgn(Delta) Delta_j ...] after instant b (the
  // first 4 rows for a 3x3 system).
  using BlockIntegrals = Matrix<Scalar, 8, kBlock>;

  // The instants of a solved block into eq. 7 with their estimates written to rows t ..
  // t + kBlock - 1 of `out`; the last instant is committed in full (commit()), so that the
  // estimator ends the block as update() would leave it.
  void commit_block(const BlockSolution& in, long t, const Histories<Scalar>& out) noexcept {
    BlockIntegrals integrals[N];
    for (int b = 0; b < kBlock; ++b) {
      if (b + 1 < kBlock) {
        for (int i = 0; i < N; ++i) {
          if (is_reduced(i)) {
            last_.accumulate(in.fed[i].col(b).template head<4>(), in.decay3(b), config_.dt);
          } else {
            full_[static_cast<std::size_t>(i)].accumulate(in.fed[i].col(b), in.decay4(b), config_.dt);
          }
        }
        ++samples_;
      } else {
        commit(in, b);
      }
      for (int i = 0; i < N; ++i) {
        if (is_reduced(i)) {
          integrals[i].col(b).template head<4>() = last_.integrals();
        } else {
          integrals[i].col(b) = full_[static_cast<std::size_t>(i)].integrals();
        }
      }
    }
    write_block(integrals, t, out);
  }

  // collect() for the kBlock instants of a block, lane by lane with the same operations
  // (RatioEstimator::packed_estimates(): one reciprocal, then products), written to rows t ..
  // t + kBlock - 1 of `out`.
  void write_block(const BlockIntegrals* integrals, long t, const Histories<Scalar>& out) const noexcept {
    using Lanes = BlockLanes;
    using Ops = LaneOps<Scalar, kBlock>;
    const Lanes zero = Lanes::Zero(), nan = Lanes::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    // row t + b of a T x Cols history from lane b, from column c on
    const auto put = [t](Scalar* history, int cols, int c, const Lanes& x) {
      for (int b = 0; b < kBlock; ++b) history[(t + b) * cols + c] = x(b);
    };
    Lanes right_spring = nan;  // k_{i+1} from DOF i, for the fusion at DOF i + 1
    for (int i = 0; i < N; ++i) {
      // [I^2 |Delta|, m_i, c_i, k_i, k_{i+1}] numerators in lanes (k_{i+1}: a full DOF only)
      Lanes I[8];
      const bool reduced = is_reduced(i);
      if (reduced) {
        transpose_to_lanes<4>(integrals[i].data(), 8, I);
      } else {
        transpose_to_lanes<8>(integrals[i].data(), 8, I);
      }
      const Lanes inv = Lanes::Ones() / I[0];
      // valid: a trusted sample has entered (I^2 |Delta| > 0)
      const Lanes m = Ops::if_less(zero, I[0], Lanes(I[1] * inv), nan);
      const Lanes c = Ops::if_less(zero, I[0], Lanes(I[2] * inv), nan);
      const Lanes k_left = I[3] * inv;
      const Lanes k_right = reduced ? nan : Lanes(I[4] * inv);
      // k_i: this DOF's estimate, fused with DOF i-1's estimate of the same spring (if valid)
      const Lanes fused = Ops::if_equal(right_spring, right_spring, Lanes(Scalar(0.5) * (k_left + right_spring)), k_left);
      const Lanes k_i = Ops::if_less(zero, I[0], fused, right_spring);
      right_spring = Ops::if_less(zero, I[0], k_right, nan);
      put(out.mass, N, i, m);
      put(out.damping, N, i, c);
      put(out.stiffness, N + 1, i, k_i);
      for (int b = 0; b < kBlock; ++b) out.valid[(t + b) * N + i] = I[0](b) > Scalar(0);
    }
    put(out.stiffness, N + 1, N, free_end() ? zero : right_spring);
    for (int b = 0; b < kBlock; ++b) out.status[t + b] = static_cast<std::int8_t>(Status::kOk);
  }

  // lanes[r](b) = src[b * stride + r], r < Rows, b < kBlock: Rows consecutive states of one
  // signal at the kBlock instants of a block (src: column-major, one column per instant) as
  // lanes. Square tiles of one SIMD register are transposed in registers (Eigen's ptranspose:
  // 2 x 2 in SSE2, 4 x 4 in AVX, 8 x 8 in AVX-512); element by element where the register
  // does not tile the block (half registers would be written and then read as one, which
  // stalls the store-to-load forwarding).
  // (GCC warns that a SIMD type's alignment attribute is dropped as a template argument, as
  // Eigen's own packet code does everywhere; Eigen silences it in its headers, we here.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
#endif
  template <int Rows, class Lanes>
  static void transpose_to_lanes(const Scalar* src, int stride, Lanes* lanes) noexcept {
    using Packet = typename Eigen::internal::packet_traits<Scalar>::type;
    constexpr int kWidth = Eigen::internal::unpacket_traits<Packet>::size;
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<Scalar, double> && kWidth == 8 && Rows == 4 && kBlock == 8) {
      // Four rows in AVX-512 (a single DOF's force): two 4 x 4 tiles of 256 bits, each row's
      // two halves joined into one 512-bit register before it is stored.
      using Half = Eigen::internal::Packet4d;
      Eigen::internal::PacketBlock<Half, 4> low, high;
      for (int j = 0; j < 4; ++j) {
        low.packet[j] = Eigen::internal::ploadu<Half>(src + j * stride);
        high.packet[j] = Eigen::internal::ploadu<Half>(src + (4 + j) * stride);
      }
      Eigen::internal::ptranspose(low);
      Eigen::internal::ptranspose(high);
      for (int r = 0; r < 4; ++r)
        _mm512_storeu_pd(lanes[r].data(), _mm512_insertf64x4(_mm512_castpd256_pd512(low.packet[r]), high.packet[r], 1));
      return;
    }
#endif
    if constexpr (kWidth > 1 && Rows % kWidth == 0 && kBlock % kWidth == 0) {
      for (int r0 = 0; r0 < Rows; r0 += kWidth) {
        for (int b0 = 0; b0 < kBlock; b0 += kWidth) {
          Eigen::internal::PacketBlock<Packet, kWidth> tile;
          for (int j = 0; j < kWidth; ++j)
            tile.packet[j] = Eigen::internal::ploadu<Packet>(src + (b0 + j) * stride + r0);
          Eigen::internal::ptranspose(tile);
          for (int j = 0; j < kWidth; ++j) Eigen::internal::pstoreu(lanes[r0 + j].data() + b0, tile.packet[j]);
        }
      }
    } else {
      for (int r = 0; r < Rows; ++r)
        for (int b = 0; b < kBlock; ++b) lanes[r](b) = src[b * stride + r];
    }
  }
  // columns(r, b) = lanes[r](b) for r < Rows: the transpose of transpose_to_lanes(), in square
  // tiles of a register of at most 4 scalars where they tile the block.
  template <int Rows, class Lanes, class Columns>
  static void lanes_to_columns(const Lanes* lanes, Columns& columns) noexcept {
    using Packet = typename Eigen::internal::find_best_packet<Scalar, 4>::type;
    constexpr int kWidth = Eigen::internal::unpacket_traits<Packet>::size;
    if constexpr (kWidth > 1 && Rows % kWidth == 0 && kBlock % kWidth == 0) {
      for (int r0 = 0; r0 < Rows; r0 += kWidth) {
        for (int b0 = 0; b0 < kBlock; b0 += kWidth) {
          Eigen::internal::PacketBlock<Packet, kWidth> tile;
          for (int j = 0; j < kWidth; ++j) tile.packet[j] = Eigen::internal::ploadu<Packet>(lanes[r0 + j].data() + b0);
          Eigen::internal::ptranspose(tile);
          for (int j = 0; j < kWidth; ++j) Eigen::internal::pstoreu(&columns(r0, b0 + j), tile.packet[j]);
        }
      }
    } else {
      for (int r = 0; r < Rows; ++r)
        for (int b = 0; b < kBlock; ++b) columns(r, b) = lanes[r](b);
    }
  }

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

  // signal_rows() for kBlock instants: column c of the rows holds R(q, q + c), q < Rows, with
  // the operations of signal_rows() (J_s - a J_(s+1)) + b J_(s+2).
  template <int Cols, int Rows, class Lanes>
  static void lane_rows(const Lanes* J, Lanes* rows) noexcept {
    for (int c = 0; c < Cols; ++c) {
      for (int q = 0; q < Rows; ++q) {
        rows[c * 4 + q] =
            J[c + q] - static_cast<Scalar>(kRowA[q]) * J[c + q + 1] + static_cast<Scalar>(kRowB[q]) * J[c + q + 2];
      }
    }
  }

  // DOF i's systems for kBlock instants, solved and weighed for eq. 7 into `out`, with the
  // arithmetic of DofEstimator::update(); the last lane's system is what system() reports.
  template <int M, class Lanes, class Dof>
  void solve_lanes(const Lanes* left, const Lanes* self, const Lanes* right, const Lanes* force, const Lanes& inv_tau,
                   const Lanes& samples, int i, BlockSolution& out, Dof& dof) const noexcept {
    Lanes S[M * M], s[M];
    assemble_system<M>(left, self, right, force, S, s);
    Lanes* scaled = &out.scaled[4 * i];
    cramer_lanes<M>(S, s, out.det[i], scaled);
    equilibrated_hadamard2<M>(S, out.det[i], out.h2num[i], out.h2den[i]);
    Scalar last_S[M * M], last_s[M];
    for (int e = 0; e < M * M; ++e) last_S[e] = S[e](kBlock - 1);
    for (int q = 0; q < M; ++q) last_s[q] = s[q](kBlock - 1);
    dof.set_system(last_S, last_s);
    // The numerators of the time-scaled system scaled to the physical parameters, the validity
    // rule and what eq. 7 is fed (DofEstimator::commit(), in lanes: weigh_lanes()), then one
    // packed vector per instant.
    const Lanes inv2 = inv_tau * inv_tau;
    scaled[1] = scaled[1] * inv_tau;
    for (int q = 2; q < M; ++q) scaled[q] = scaled[q] * inv2;
    constexpr int kSlots = Dof::Packed::RowsAtCompileTime;
    Lanes fed[kSlots];
    weigh_lanes<M>(out.det[i], scaled, out.h2num[i], out.h2den[i], samples, config_.validity, fed[0], &fed[1]);
    for (int q = M + 1; q < kSlots; ++q) fed[q].setZero();
    lanes_to_columns<kSlots>(fed, out.fed[i]);
  }

  // Eq. 7 estimates of every DOF into the physical views (one division per DOF, NaN where not
  // valid); an interior spring is the mean of its two DOFs' estimates, or the one that is valid.
  void collect() noexcept {
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    Scalar right_spring = nan;  // k_{i+1} from DOF i, for the fusion at DOF i + 1
    for (int i = 0; i < N; ++i) {
      // [m_i, c_i, k_i, k_{i+1}] in slots 1 .. 4 (k_{i+1}: NaN for a reduced DOF)
      Scalar m, c, k_left, k_right = nan;
      bool ok;
      if (is_reduced(i)) {
        const auto e = last_.packed_estimates();
        m = e(1), c = e(2), k_left = e(3);
        ok = last_.valid();
      } else {
        const auto e = full_[static_cast<std::size_t>(i)].packed_estimates();
        m = e(1), c = e(2), k_left = e(3), k_right = e(4);
        ok = full_[static_cast<std::size_t>(i)].valid();
      }
      valid_[i] = ok;
      mass_(i) = ok ? m : nan;
      damping_(i) = ok ? c : nan;
      // k_i: this DOF's estimate, fused with DOF i-1's estimate of the same spring.
      const bool left_ok = !std::isnan(right_spring);
      stiffness_(i) = ok ? (left_ok ? Scalar(0.5) * (k_left + right_spring) : k_left) : right_spring;
      right_spring = ok ? k_right : nan;
    }
    stiffness_(N) = free_end() ? Scalar(0) : right_spring;
  }

  Rule rule_;
  AccelChain accel_{};
  ForceChain force_{};
  typename AccelChain::Scaled accel_scaled_ = AccelChain::Scaled::Zero();
  typename ForceChain::Scaled force_scaled_ = ForceChain::Scaled::Zero();
  std::array<Matrix<Scalar, 4, 3>, N> accel_rows_{};
  std::array<Matrix<Scalar, 4, 1>, N> force_rows_{};
  std::array<DofEstimator<4, Scalar>, N> full_{};
  DofEstimator<3, Scalar> last_{};
  Vector<Scalar, N> mass_ = Vector<Scalar, N>::Zero();
  Vector<Scalar, N> damping_ = Vector<Scalar, N>::Zero();
  Vector<Scalar, N + 1> stiffness_ = Vector<Scalar, N + 1>::Zero();
  std::array<bool, N> valid_{};
  long samples_ = 0;
};

}  // namespace detail
}  // namespace algid
