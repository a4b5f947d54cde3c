#pragma once
/// @file chain_estimator.hpp
/// On-line algebraic estimator of every mass, damper and spring of an n-DOF chain (eq. 1)
/// from sampled accelerations y_i and forces u_i only (eqs. 2-7).
///
/// Two phases. Construction validates the configuration (and throws std::invalid_argument,
/// or aborts when built without exceptions; call `validate()` first there). `update()`,
/// `reseed()` and every accessor are noexcept, allocate nothing, lock nothing and are O(n).
///
/// Timing: the quadrature needs P samples around an interval, so after sample k the
/// estimates describe the window [t0, t_k - delay h], delay = P - 2 (`kDelay`).
///
/// Bad samples: a non-finite acceleration or force is discarded, the estimator reseeds (the
/// next sample is the new t0), `update()` returns Status::kBadInput and every estimate is
/// invalid (NaN) until the new window has a trusted sample.

#include "algid/dof_estimator.hpp"
#include "algid/integrator_chain.hpp"
#include "algid/types.hpp"

#include <array>
#include <cmath>
#include <limits>

namespace algid {

/// Configuration of a ChainEstimator.
template <class Scalar>
struct ChainConfig {
  Scalar dt = Scalar(1e-3);              ///< sample period [s]
  Boundary boundary = Boundary::kFixed;  ///< right end: wall (k_{n+1} estimated) or free (k_{n+1} = 0)
  ValidityRule<Scalar> validity{};       ///< when an instantaneous solution is trusted
};

/// Why a configuration is rejected (kNone: accepted).
enum class ConfigError { kNone, kBadSamplePeriod, kBadMinSamples, kBadMinHadamard };

/// Human-readable text of a ConfigError.
inline const char* to_string(ConfigError e) noexcept {
  switch (e) {
    case ConfigError::kNone: return "ok";
    case ConfigError::kBadSamplePeriod: return "dt must be finite and > 0 [s]";
    case ConfigError::kBadMinSamples: return "validity.min_samples must be >= 1";
    case ConfigError::kBadMinHadamard: return "validity.min_hadamard must be in [0, 1)";
  }
  return "unknown";
}

/// The estimator of an N-DOF chain.
/// @tparam N number of DOF (masses), >= 1.
/// @tparam Scalar double or float.
/// @tparam P quadrature points (even; 8 by default: O(h^8) chains, 6 samples of delay).
template <int N, class Scalar = double, int P = 8>
class ChainEstimator {
  static_assert(N >= 1, "a chain has at least one DOF");

 public:
  /// Integrator chains of the N accelerations (orders 1..7 needed, 8 kept) and of the N forces
  /// (1..5 needed, 6 kept): the extra order pads to the SIMD width and costs nothing.
  using AccelChain = IntegratorChain<P, kAccelOrders + 1, Scalar, N>;
  using ForceChain = IntegratorChain<P, kForceOrders + 1, Scalar, N>;
  /// The quadrature rule both are advanced with.
  using Rule = typename AccelChain::Rule;
  using Config = ChainConfig<Scalar>;
  /// Samples by which the estimates lag the newest sample.
  static constexpr int kDelay = Rule::kDelay;
  /// Number of DOF.
  static constexpr int kDofs = N;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ConfigError validate(const Config& config) noexcept {
    if (!(config.dt > Scalar(0)) || !std::isfinite(config.dt)) return ConfigError::kBadSamplePeriod;
    if (config.validity.min_samples < 1) return ConfigError::kBadMinSamples;
    if (!(config.validity.min_hadamard >= Scalar(0) && config.validity.min_hadamard < Scalar(1)))
      return ConfigError::kBadMinHadamard;
    return ConfigError::kNone;
  }

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit ChainEstimator(const Config& config) : config_(config) {
    const ConfigError e = validate(config);
    if (e != ConfigError::kNone) detail::config_error(to_string(e));
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
  Status update(const Scalar* accel, const Scalar* force) noexcept {
    for (int i = 0; i < N; ++i) {
      if (!std::isfinite(accel[i]) || !std::isfinite(force[i])) {
        reseed();
        return Status::kBadInput;
      }
    }
    ++samples_;
    const bool advanced = accel_.push(accel, rule_);
    force_.push(force, rule_);
    if (!advanced) return Status::kWarmup;
    // Everything the DOFs share at this instant, once per sample.
    const Scalar tau = static_cast<Scalar>(samples_ - P + 1) * config_.dt;
    const Scalar prev_tau = static_cast<Scalar>(samples_ - P) * config_.dt;
    Instant<Scalar> now;
    now.inv_tau = Scalar(1) / tau;
    now.h = config_.dt;
    if (N > 1) now.decay4 = RatioEstimator<4, Scalar>::decay(prev_tau, tau);  // DOF 1 is full
    if (reduced_last()) now.decay3 = RatioEstimator<3, Scalar>::decay(prev_tau, tau);
    now.samples = samples_;
    Vector<Scalar, AccelChain::kOrders + 1> inv_pow;
    inv_pow(0) = Scalar(1);
    for (int r = 1; r <= AccelChain::kOrders; ++r) inv_pow(r) = inv_pow(r - 1) * now.inv_tau;
    // Each signal's rows once: an acceleration enters its own DOF and both neighbours'.
    accel_.scaled(inv_pow, accel_scaled_);
    force_.scaled(inv_pow, force_scaled_);
    for (int i = 0; i < N; ++i) {
      signal_rows(accel_scaled_.col(i).data(), accel_rows_[i]);
      signal_rows(force_scaled_.col(i).data(), force_rows_[i]);
    }
    for (int i = 0; i < N; ++i) {
      const auto* left = i > 0 ? &accel_rows_[i - 1] : nullptr;
      const auto* right = i + 1 < N ? &accel_rows_[i + 1] : nullptr;
      if (i == N - 1 && reduced_last()) {
        last_.update(left, accel_rows_[i], right, force_rows_[i], now, config_.validity);
      } else {
        full_[i].update(left, accel_rows_[i], right, force_rows_[i], now, config_.validity);
      }
    }
    collect();
    return Status::kOk;
  }

  /// Same as update(const Scalar*, const Scalar*) for Eigen vectors.
  /// @realtime no allocation, no throw
  Status update(const Vector<Scalar, N>& accel, const Vector<Scalar, N>& force) noexcept {
    return update(accel.data(), force.data());
  }

  /// Eq. 7 estimates of the masses m_i [kg] (NaN where not valid).
  const Vector<Scalar, N>& mass() const noexcept { return mass_; }
  /// Eq. 7 estimates of the dampings c_i [N s/m].
  const Vector<Scalar, N>& damping() const noexcept { return damping_; }
  /// Fused eq. 7 estimates of the springs k_1 .. k_{n+1} [N/m]: an interior spring is the mean
  /// of the estimates of its two DOF (those that are valid). For N = 1 with walls, k_1 holds
  /// the identifiable sum k_1 + k_2 and k_2 is NaN; with a free end k_{n+1} = 0.
  const Vector<Scalar, N + 1>& stiffness() const noexcept { return stiffness_; }
  /// Per-DOF validity of the eq. 7 estimates.
  const std::array<bool, N>& valid() const noexcept { return valid_; }
  /// True when every DOF is valid.
  bool all_valid() const noexcept {
    for (bool v : valid_)
      if (!v) return false;
    return true;
  }

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
  /// Window length t_k - delay h - t0 [s] that the current estimates describe (0 before).
  Scalar window() const noexcept {
    return samples_ >= P ? static_cast<Scalar>(samples_ - P + 1) * config_.dt : Scalar(0);
  }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 private:
  bool free_end() const noexcept { return config_.boundary == Boundary::kFree; }
  bool reduced_last() const noexcept { return N == 1 || free_end(); }
  bool is_reduced(int i) const noexcept { return i == N - 1 && reduced_last(); }

  // Eq. 7 estimates of every DOF into the physical views (one division per DOF); an interior
  // spring is the mean of its two DOFs' estimates, or the one that is valid.
  void collect() noexcept {
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    Scalar right_spring = nan;  // k_{i+1} from DOF i, for the fusion at DOF i + 1
    for (int i = 0; i < N; ++i) {
      const Vector<Scalar, 4> t = theta(i);  // NaN where not valid
      valid_[i] = is_reduced(i) ? last_.valid() : full_[i].valid();
      mass_(i) = t(0);
      damping_(i) = t(1);
      // k_i: this DOF's estimate, fused with DOF i-1's estimate of the same spring.
      const bool left_ok = !std::isnan(right_spring);
      stiffness_(i) = valid_[i] ? (left_ok ? Scalar(0.5) * (t(2) + right_spring) : t(2)) : right_spring;
      right_spring = t(3);
    }
    stiffness_(N) = free_end() ? Scalar(0) : right_spring;
  }

  Config config_;
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

}  // namespace algid
