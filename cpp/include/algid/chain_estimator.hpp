#pragma once
/// @file chain_estimator.hpp
/// On-line algebraic estimator of every mass, damper and spring of an n-DOF chain (eq. 1)
/// from sampled accelerations y_i and forces u_i only (eqs. 2-7), with a force on every DOF or
/// on one DOF only (below, "One force").
///
/// Two phases. Construction validates the configuration (and throws std::invalid_argument,
/// or aborts when built without exceptions; call `validate()` first there) and, for a chain
/// whose size is known only at run time (N = Dynamic), allocates everything it will use.
/// `update()`, `reseed()`, `run()`, `record()` and every accessor are noexcept, allocate
/// nothing, lock nothing and are O(n).
///
/// Timing: the quadrature needs P samples around an interval, so after sample k the
/// estimates describe the window [t0, t_k - delay h], delay = P - 2 (`kDelay`).
///
/// Bad samples: a non-finite acceleration or force is discarded, the estimator reseeds (the
/// next sample is the new t0), `update()` returns Status::kBadInput and every estimate is
/// invalid (NaN) until the new window has a trusted sample. The same happens when a finite
/// sample is so large that a system of eq. 5 overflows (its determinant is no longer finite):
/// nothing later in that window could be trusted. A DOF is valid only while all its eq. 7
/// estimates are finite.
///
/// Layout: every DOF side by side, one per SIMD lane, for every step of every sample. DOF i
/// sits in lane i % W of register i / W (W = lane_width(): 2 doubles with SSE2, 4 with AVX2
/// and AVX-512, fewer for a chain that fills fewer), and so do its acceleration and force.
/// Per sample:
///   1. the integrator chains of all accelerations and all forces advance, W signals per
///      register operation (IntegratorLanes);
///   2. each signal's rows of eq. 5 are formed from its time-scaled integrals (signal_row());
///      a DOF's spring columns subtract the rows of its neighbours, which are the same
///      registers moved one lane (LaneOps::from_previous / from_next), with zero lanes beyond
///      the walls; the registers are visited in order, each with the rows of its two
///      neighbours, so nothing of size n is formed per sample;
///   3. the systems of W DOF are solved at once by Cramer's rule (cramer_lanes()), their
///      equilibrated Hadamard ratios computed, the validity rule applied lane by lane, and
///      eq. 7 advanced (RatioLanes);
///   4. the estimates are formed in the lanes they are read from (mass(), damping(),
///      stiffness() view them in place) and the interior springs fused.
/// A DOF with a 3x3 system (a free right end) is embedded as the 4x4 system with row and
/// column 4 of the identity, which has the same determinant, the same first three Cramer
/// numerators and the same equilibrated Hadamard ratio; its lane of eq. 7 decays with the 3x3
/// exponent. A chain of one DOF (N = 1) solves its 3x3 system as it is. Lanes beyond the last
/// DOF carry zero signals and are never valid. run() and record() are update() sample by
/// sample: the lanes already hold the DOF side by side.
///
/// One force. A DOF is *forced* from the first sample since t0 at which its force is not zero
/// (before it every integral of its force is zero); reseed() forgets it. The equation of a DOF
/// without force is homogeneous and determines only the ratios c_i / m_i, k_i / m_i,
/// k_{i+1} / m_i: its lane solves the same 4x4 layout with its last row replaced by m_i = 1
/// (row 3; row 2 for the 3x3 DOF of a free end) and no force, i.e. rows 0-2 of eq. 5 in the
/// columns c_i, k_i, k_{i+1} with the mass column on the right side, and eq. 7 averages those
/// ratios, weighted by the determinant of that system (tau^14 |det S|, tau^8 at a free end:
/// homogeneous_decay). A DOF whose force appears later restarts its eq. 7 then. The scale
/// then passes along the springs: a neighbour with a scale estimates the spring they share, so
/// m_i = k_shared / (k_shared / m_i), and c_i, the other spring follow; from each forced DOF
/// outwards both ways, each DOF taking the scale of the nearest forced DOF (equally near ones:
/// the mean of the two masses). The lanes of eq. 7 then hold the scaled estimates. A spring
/// between a DOF and the neighbour that took its scale through it is the scaled side's number
/// (the other's is the same number); between two DOF that carry their own scale, the mean. A
/// DOF that no forced DOF reaches through valid estimates (no force at all, a spring estimated
/// as 0 on the way, n = 1) is NaN and not valid. This runs per sample after eq. 7 (O(n)) only
/// while some DOF is without force (detail/one_force.hpp: OneForce).
///
/// Interface:
///   - `static ConfigError validate(const Config&, int n = N)`,
///     `explicit ChainEstimator(const Config&, int n = N)` (n: the DOF, any n >= 1 for
///     N = Dynamic, N itself otherwise);
///   - `Status update(const Scalar* accel, const Scalar* force)` (n values each, [m/s^2], [N]),
///     `reseed()`, `run(accel, force, T, observe)` (T x n row-major, `observe(t, status)`
///     after each sample), `record(accel, force, T, histories)` (the estimates after each
///     sample written into caller-owned arrays: Histories, histories.hpp);
///   - `mass()`, `damping()` (n), `stiffness()` (n + 1: k_1 .. k_{n+1}, an interior spring the
///     mean of its two DOF's estimates; k_1 = k_1 + k_2 and k_2 NaN for n = 1 with walls,
///     k_{n+1} = 0 at a free end), `valid()` (n flags), `all_valid()`;
///   - per DOF i (0-based): `theta(i)` = eq. 7 [m_i, c_i, k_i, k_{i+1}] (scaled as above for a DOF
///     without force), `theta_instant(i)` (the Cramer solution of the last sample: the ratios
///     [1, c_i / m_i, k_i / m_i, k_{i+1} / m_i] for a DOF without force), `hadamard(i)`,
///     `instant_valid(i)`, `forced(i)`;
///   - `dofs()`, `samples()`, `window()` [s], `config()`, `kDelay`, `kDofs`.

#include "algid/algebraic_system.hpp"
#include "algid/chain_config.hpp"
#include "algid/cramer.hpp"
#include "algid/detail/lanes.hpp"
#include "algid/detail/one_force.hpp"
#include "algid/detail/storage.hpp"
#include "algid/histories.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/quadrature.hpp"
#include "algid/ratio_estimator.hpp"
#include "algid/types.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

namespace algid {

/// Check a configuration for a chain of `n` DOF without side effects.
/// @realtime no allocation, no throw
template <class Scalar>
ConfigError validate(const ChainConfig<Scalar>& config, int n) noexcept {
  return n < 1 ? ConfigError::kBadDofs : validate(config);
}

/// The estimator of an N-DOF chain; its interface is in the file comment.
/// @tparam N number of DOF (masses), >= 1, or Dynamic (given to the constructor).
/// @tparam Scalar double or float.
/// @tparam P quadrature points (even; 8 by default: O(h^8) chains, 6 samples of delay).
template <int N, class Scalar = double, int P = 8>
class ChainEstimator {
  static_assert(N >= 1 || N == Dynamic, "a chain has at least one DOF");

 public:
  using Config = ChainConfig<Scalar>;
  /// Samples by which the estimates lag the newest sample.
  static constexpr int kDelay = P - 2;
  /// Number of DOF (Dynamic: see dofs()).
  static constexpr int kDofs = N;
  /// Lanes per register (DOF side by side): the widest for a run-time size.
  static constexpr int kLanes = detail::lane_width<N == Dynamic ? (1 << 30) : N, Scalar>();
  /// Registers of DOF (and of signals), and of the springs k_1 .. k_{N+1}.
  static constexpr int kRegisters = N == Dynamic ? Dynamic : (N + kLanes - 1) / kLanes;
  static constexpr int kSpringRegisters = N == Dynamic ? Dynamic : N / kLanes + 1;
  /// Size of the DOF's systems of eq. 5 (3 for a chain of one DOF, whose 3x3 system is solved
  /// as it is, also when N = Dynamic; 4 otherwise, a free end embedded, see the file comment).
  static constexpr int kSystem = N == 1 ? 3 : 4;
  using L = detail::Lanes<Scalar, kLanes>;
  using Ops = detail::LaneOps<Scalar, kLanes>;
  static_assert(sizeof(L) == kLanes * sizeof(Scalar), "registers of lanes are contiguous: mass() views them");
  /// Integrals of the accelerations (J_0 .. J_7 needed) and of the forces (J_0 .. J_5).
  using AccelChain = IntegratorLanes<P, kAccelOrders, Scalar, kLanes, kRegisters>;
  using ForceChain = IntegratorLanes<P, kForceOrders, Scalar, kLanes, kRegisters>;
  /// The quadrature rule both are advanced with.
  using Rule = InterpolatoryRule<P, kAccelOrders, Scalar>;
  static_assert(kDelay == Rule::kDelay, "the quadrature's delay");

  /// Check a configuration for `n` DOF without side effects. @realtime no allocation, no throw
  static ConfigError validate(const Config& config, int n = N) noexcept {
    return N != Dynamic && n != N ? ConfigError::kBadDofs : algid::validate(config, n);
  }

  /// Configure for `n` DOF (N itself unless N is Dynamic) and allocate (N = Dynamic only);
  /// throws std::invalid_argument on a bad configuration.
  explicit ChainEstimator(const Config& config, int n = N) : config_(config), n_(detail::fixed_or<N>(n)) {
    const ConfigError e = validate(config, n);
    if (e != ConfigError::kNone) detail::config_error(to_string(e));
    const int registers = (n_ + kLanes - 1) / kLanes, springs = n_ / kLanes + 1;
    Rule rule;
    rule.configure(config.dt);
    weights_.configure(rule);
    accel_.configure(registers);
    force_.configure(registers);
    for (auto* s : {&det_, &weight_, &hadamard2_num_, &hadamard2_den_, &numerator_[0], &numerator_[1], &numerator_[2],
                    &numerator_[3]})
      s->resize(registers);
    ratio_.resize(registers);
    one_force_.configure(n_);
    for (auto& s : estimate_) s.resize(springs);
    spring_.resize(springs);
    valid_.resize(n_);
    reduced_.setZero();
    if (reduced_last()) reduced_((n_ - 1) % kLanes) = Scalar(1);
    reseed();
  }

  /// Restart at a new t0: the next sample is the first of a new window.
  /// @realtime no allocation, no throw
  void reseed() noexcept {
    accel_.reset();
    force_.reset();
    const L nan = L::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    for (int g = 0; g < registers(); ++g) ratio_[g].reset();
    for (auto* s : {&det_, &weight_, &hadamard2_num_, &numerator_[0], &numerator_[1], &numerator_[2], &numerator_[3]})
      s->fill(L::Zero());
    hadamard2_den_.fill(L::Ones());
    for (auto& s : estimate_) s.fill(nan);
    spring_.fill(nan);
    if (free_end()) spring_[n_ / kLanes](n_ % kLanes) = Scalar(0);
    valid_.fill(false);
    one_force_.reset();
  }

  /// Consume one simultaneous sample of the accelerations [m/s^2] and forces [N].
  /// @realtime no allocation, no throw, O(n)
  ALGID_FLATTEN Status update(const Scalar* accel, const Scalar* force) noexcept {
    if (!finite(accel, force)) {
      reseed();
      return Status::kBadInput;
    }
    one_force_.note(force, ratio_);
    const bool advanced = accel_.push(accel, n_, weights_);
    force_.push(force, n_, weights_);
    if (!advanced) return Status::kWarmup;

    const Instant now = instant();
    // Registers in order, each with its neighbours' spring rows (zero lanes at the walls).
    Rows rows[2];
    rows_of(0, now, rows[0]);
    L left[4];
    for (int q = 0; q < 4; ++q) left[q].setZero();
    const int last = registers() - 1;
    for (int g = 0; g <= last; ++g) {
      Rows& self = rows[g & 1];
      Rows& right = rows[(g + 1) & 1];
      if (g < last) {
        rows_of(g + 1, now, right);
      } else {
        for (int q = 0; q < 4; ++q) right.spring[q].setZero();
      }
      if (kSystem == 3 || (N == Dynamic && n_ == 1)) {
        solve<3>(g, left, self, right.spring, now);
      } else {
        solve<4>(g, left, self, right.spring, now);
      }
      for (int q = 0; q < 4; ++q) left[q] = self.spring[q];
    }
    if (!finite_systems()) {  // a finite sample so large that the window's integrals overflow
      reseed();
      return Status::kBadInput;
    }
    collect();
    return Status::kOk;
  }

  /// Same as update(const Scalar*, const Scalar*) for Eigen vectors.
  /// @realtime no allocation, no throw
  template <class A, class F>
  Status update(const Eigen::MatrixBase<A>& accel, const Eigen::MatrixBase<F>& force) noexcept {
    return update(accel.derived().data(), force.derived().data());
  }

  /// Consume a record of T samples (T x n, row-major) and call `observe(t, status)` after each.
  /// @realtime no allocation; no throw unless `observe` throws
  template <class Observer>
  void run(const Scalar* accel, const Scalar* force, long T, Observer&& observe) {
    for (long t = 0; t < T; ++t) observe(t, update(accel + t * n_, force + t * n_));
  }

  /// Consume a record of T samples (T x n, row-major, as run()) and write the estimates after
  /// each sample into row t of `out` (see Histories). @realtime no allocation, no throw
  void record(const Scalar* accel, const Scalar* force, long T, const Histories<Scalar>& out) noexcept {
    run(accel, force, T, [&](long t, Status s) { write_row(t, s, out); });
  }

  /// Write row t of `out` (see Histories) from the accessors, after a sample of status `s`.
  /// @realtime no allocation, no throw
  void write_row(long t, Status s, const Histories<Scalar>& out) const noexcept {
    out.status[t] = static_cast<std::int8_t>(s);
    for (int i = 0; i < n_; ++i) {
      out.mass[t * n_ + i] = lane(estimate_[0], i);
      out.damping[t * n_ + i] = lane(estimate_[1], i);
      out.valid[t * n_ + i] = valid_[i];
    }
    for (int j = 0; j <= n_; ++j) out.stiffness[t * (n_ + 1) + j] = lane(spring_, j);
  }

  /// Eq. 7 estimates of the masses m_i [kg] (NaN where not valid), viewed in place.
  Eigen::Map<const Vector<Scalar, N>> mass() const noexcept { return view<N>(estimate_[0], n_); }
  /// Eq. 7 estimates of the dampings c_i [N s/m].
  Eigen::Map<const Vector<Scalar, N>> damping() const noexcept { return view<N>(estimate_[1], n_); }
  /// Fused eq. 7 estimates of the springs k_1 .. k_{n+1} [N/m] (see the file comment).
  Eigen::Map<const Vector<Scalar, N == Dynamic ? Dynamic : N + 1>> stiffness() const noexcept {
    return view<N == Dynamic ? Dynamic : N + 1>(spring_, n_ + 1);
  }
  /// Per-DOF validity of the eq. 7 estimates (n flags).
  Eigen::Map<const Eigen::Array<bool, N, 1>> valid() const noexcept {
    return Eigen::Map<const Eigen::Array<bool, N, 1>>(valid_.data(), n_);
  }
  /// True when every DOF is valid.
  bool all_valid() const noexcept { return valid().all(); }

  /// Eq. 7 estimate [m_i, c_i, k_i, k_{i+1}] of DOF i (0-based), scaled through its springs for
  /// a DOF without force; NaN while not valid, and in slot 3 of a 3x3 DOF.
  Vector<Scalar, 4> theta(int i) const noexcept {
    Vector<Scalar, 4> out;
    for (int j = 0; j < 4; ++j) out(j) = lane(estimate_[j], i);
    return out;
  }
  /// Instantaneous Cramer solution of eq. 5 for DOF i (0-based), same layout as theta(); for a
  /// DOF without force, the ratios to its mass [1, c_i / m_i, k_i / m_i, k_{i+1} / m_i].
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
  /// Whether DOF i (0-based) has had a non-zero force since t0; false: its equation is
  /// homogeneous and its scale comes through its springs (file comment, "One force").
  bool forced(int i) const noexcept { return one_force_.forced(i); }
  /// Whether DOF i's last instantaneous solution was trusted.
  bool instant_valid(int i) const noexcept { return lane(weight_, i) > Scalar(0); }

  /// Number of DOF.
  int dofs() const noexcept { return detail::fixed_or<N>(n_); }
  /// Samples consumed since t0.
  long samples() const noexcept { return accel_.count(); }
  /// Window length t_k - delay h - t0 [s] that the current estimates describe (0 before).
  Scalar window() const noexcept {
    return samples() >= P ? static_cast<Scalar>(samples() - P + 1) * config_.dt : Scalar(0);
  }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 private:
  template <int Size>
  using Registers = detail::Storage<L, Size>;

  // What every DOF shares at this interval end.
  struct Instant {
    Scalar inv_pow[kAccelOrders + 1];  // tau^-r
    Scalar decay4, decay3;             // ratio_decay<4>, <3> from the previous tau
    Scalar homogeneous4, homogeneous3;  // homogeneous_decay<4>, <3> (the DOF without force)
    L samples;                         // samples consumed since t0, in every lane
  };
  static constexpr int kRows = kSystem;  // rows of eq. 5 formed (3 of them used when n = 1)
  // One register's rows of eq. 5: acceleration columns (mass, damping, spring) and force.
  struct Rows {
    L mass[4], damping[4], spring[4], force[4];
  };

  int registers() const noexcept { return kRegisters == Dynamic ? (n_ + kLanes - 1) / kLanes : kRegisters; }
  int spring_registers() const noexcept { return kSpringRegisters == Dynamic ? n_ / kLanes + 1 : kSpringRegisters; }
  bool free_end() const noexcept { return config_.boundary == Boundary::kFree; }
  // The last DOF solves a 3x3 system: a free right end, or n = 1 with walls (k_1 + k_2).
  bool reduced_last() const noexcept { return n_ == 1 || free_end(); }
  bool is_reduced(int i) const noexcept { return i == n_ - 1 && reduced_last(); }

  bool finite(const Scalar* accel, const Scalar* force) const noexcept {
    bool ok = true;
    for (int e = 0; e < n_; ++e) ok &= std::isfinite(accel[e]) & std::isfinite(force[e]);
    return ok;
  }

  // Every system of eq. 5 has a finite determinant (false once the integrals overflowed).
  bool finite_systems() const noexcept {
    bool ok = true;
    for (int g = 0; g < registers(); ++g) ok &= det_[g].isFinite().all();
    return ok;
  }

  template <int Size>
  static Scalar lane(const Registers<Size>& registers, int i) noexcept {
    return registers[i / kLanes](i % kLanes);
  }
  template <int Rows, int Size>
  static Eigen::Map<const Vector<Scalar, Rows>> view(const Registers<Size>& registers, int size) noexcept {
    return Eigen::Map<const Vector<Scalar, Rows>>(registers.data()->data(), size);
  }

  Instant instant() const noexcept {
    Instant now;
    const long samples = accel_.count();
    const Scalar intervals = static_cast<Scalar>(samples - P);
    const Scalar prev_tau = intervals * config_.dt;
    const Scalar tau = (intervals + Scalar(1)) * config_.dt;
    const Scalar inv_tau = Scalar(1) / tau;
    now.inv_pow[0] = Scalar(1);
    for (int r = 1; r <= kAccelOrders; ++r) now.inv_pow[r] = now.inv_pow[r - 1] * inv_tau;
    now.decay4 = ratio_decay<4>(prev_tau, tau);
    now.decay3 = reduced_last() ? ratio_decay<3>(prev_tau, tau) : now.decay4;
    now.homogeneous4 = homogeneous_decay<4>(prev_tau, tau);
    now.homogeneous3 = reduced_last() ? homogeneous_decay<3>(prev_tau, tau) : now.homogeneous4;
    now.samples = L::Constant(static_cast<Scalar>(samples));
    return now;
  }

  // The rows of register g's signals (signal_row()).
  void rows_of(int g, const Instant& now, Rows& out) const noexcept {
    L J[kAccelOrders + 1];
    accel_.scaled(g, now.inv_pow, J);
    for (int q = 0; q < kRows; ++q) {
      out.mass[q] = signal_row(J, q, q);
      out.damping[q] = signal_row(J, q, q + 1);
      out.spring[q] = signal_row(J, q, q + 2);
    }
    L F[kForceOrders + 1];
    force_.scaled(g, now.inv_pow, F);
    for (int q = 0; q < kRows; ++q) out.force[q] = signal_row(F, q, q);
  }

  // Eq. 5 of the DOF of register g, M x M (column-major S, s): springs k_i, k_{i+1} against
  // the neighbours' rows one lane away (`left`, `right`: the spring rows of registers g -+ 1).
  // Then Cramer, the validity rule and eq. 7.
  template <int M>
  void solve(int g, const L* left, const Rows& self, const L* right, const Instant& now) noexcept {
    L S[M * M], s[M];
    for (int q = 0; q < M; ++q) {
      S[0 * M + q] = self.mass[q];
      S[1 * M + q] = self.damping[q];
      S[2 * M + q] = self.spring[q] - Ops::from_previous(self.spring[q], left[q]);
      if constexpr (M == 4) S[3 * M + q] = self.spring[q] - Ops::from_next(self.spring[q], right[q]);
      s[q] = self.force[q];
    }
    const bool has_reduced = M == 4 && reduced_last() && g == (n_ - 1) / kLanes;
    const L zero = L::Zero();
    if constexpr (M == 4) {
      if (has_reduced) {  // the 3x3 DOF: row and column 4 of the identity
        for (int q = 0; q < 3; ++q) {
          S[3 * 4 + q] = Ops::if_less(zero, reduced_, zero, S[3 * 4 + q]);
          S[q * 4 + 3] = Ops::if_less(zero, reduced_, zero, S[q * 4 + 3]);
        }
        S[15] = Ops::if_less(zero, reduced_, L::Ones(), S[15]);
        s[3] = Ops::if_less(zero, reduced_, zero, s[3]);
      }
      if (!one_force_.all_forced()) one_force_.homogeneous_rows(g, has_reduced ? reduced_ : zero, S, s);
    }
    L det, numerator[M], h2num, h2den;
    cramer_lanes<M>(S, s, det, numerator);
    equilibrated_hadamard2<M>(S, det, h2num, h2den);
    // Numerators of the physical parameters (tau scaling undone, see algebraic_system.hpp).
    const Scalar inv_tau = now.inv_pow[1], inv_tau2 = now.inv_pow[2];
    L scaled[M];
    scaled[0] = numerator[0];
    scaled[1] = numerator[1] * inv_tau;
    for (int j = 2; j < M; ++j) scaled[j] = numerator[j] * inv_tau2;
    L weight, weighted[kSystem];  // eq. 7 keeps kSystem numerators: the others stay 0
    for (int j = M; j < kSystem; ++j) weighted[j].setZero();
    weigh_lanes<M>(det, scaled, h2num, h2den, now.samples, config_.validity, weight, weighted);
    L rho = M == 3        ? L::Constant(now.decay3)
            : has_reduced ? Ops::if_less(zero, reduced_, L::Constant(now.decay3), L::Constant(now.decay4))
                          : L::Constant(now.decay4);
    if (M == 4 && !one_force_.all_forced()) {
      const L homogeneous = has_reduced ? Ops::if_less(zero, reduced_, L::Constant(now.homogeneous3),
                                                       L::Constant(now.homogeneous4))
                                        : L::Constant(now.homogeneous4);
      rho = one_force_.select(g, rho, homogeneous);
    }
    auto& ratio = ratio_[g];
    ratio.add(rho, Scalar(0.5) * config_.dt, weight, weighted);
    // Eq. 7 estimates where valid (NaN elsewhere), in the lanes the accessors read.
    L estimate[M];
    estimates_lanes<M>(ratio.denominator(), ratio.numerators(), estimate);
    for (int j = 0; j < M; ++j) estimate_[j][g] = estimate[j];
    if (has_reduced)
      estimate_[3][g] = Ops::if_less(zero, reduced_, L::Constant(std::numeric_limits<Scalar>::quiet_NaN()),
                                     estimate_[3][g]);
    det_[g] = det;
    weight_[g] = weight;
    hadamard2_num_[g] = h2num;
    hadamard2_den_[g] = h2den;
    for (int j = 0; j < M; ++j) numerator_[j][g] = scaled[j];
  }

  // The fused springs and the validity flags from the eq. 7 estimates of every lane, after the
  // DOF without force have their scale (OneForce::propagate()): k_i is the mean of DOF i's
  // estimate (slot 2) and DOF i-1's (slot 3) where both are numbers, else the one that is; where
  // one of the two DOF took its scale through k_i alone, the other's (OneForce::carried_springs());
  // k_{n+1} = 0 at a free end.
  void collect() noexcept {
    if (!one_force_.all_forced()) one_force_.propagate(estimate_);
    const L nan = L::Constant(std::numeric_limits<Scalar>::quiet_NaN());
    const int dof_registers = registers();
    for (int g = 0; g < spring_registers(); ++g) {
      const bool dof = g < dof_registers;
      const L own = dof ? estimate_[2][g] : nan;
      const L left = Ops::from_previous(dof ? estimate_[3][g] : nan, g > 0 ? estimate_[3][g - 1] : nan);
      spring_[g] = Ops::if_equal(own, own, Ops::if_equal(left, left, Scalar(0.5) * (own + left), own), left);
    }
    if (!one_force_.all_forced()) one_force_.carried_springs(estimate_, spring_);
    if (free_end()) spring_[n_ / kLanes](n_ % kLanes) = Scalar(0);
    // Valid: eq. 7 has weight, and every estimate of the DOF is a number.
    for (int i = 0; i < n_; ++i)
      valid_[i] = ratio_[i / kLanes].denominator()(i % kLanes) > Scalar(0) && std::isfinite(lane(estimate_[0], i)) &&
                  std::isfinite(lane(estimate_[1], i)) && std::isfinite(lane(estimate_[2], i)) &&
                  (is_reduced(i) || std::isfinite(lane(estimate_[3], i)));
  }

  Config config_;
  int n_;
  LaneWeights<P, kAccelOrders, Scalar, kLanes> weights_;
  AccelChain accel_{};
  ForceChain force_{};
  L reduced_ = L::Zero();  // 1 in the lane of a 3x3 DOF, in the last register of DOF
  detail::Storage<RatioLanes<Scalar, kLanes, kSystem>, kRegisters> ratio_{};
  // The last sample's solution, lane by lane: det S, the eq. 7 weight (> 0: trusted), the
  // squared Hadamard ratio as num / den, the tau-unscaled Cramer numerators.
  Registers<kRegisters> det_{}, weight_{}, hadamard2_num_{}, hadamard2_den_{};
  Registers<kRegisters> numerator_[4]{};
  // Eq. 7 estimates (slot j of every DOF), and the fused springs, read in place.
  Registers<kSpringRegisters> estimate_[4]{};
  Registers<kSpringRegisters> spring_{};
  detail::Storage<bool, N> valid_{};
  // Which DOF are forced, and the scale of the others (file comment, "One force").
  detail::OneForce<Scalar, kLanes, kRegisters, N> one_force_{};
};

}  // namespace algid
