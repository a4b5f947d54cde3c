#pragma once
/// @file chain_common.hpp
/// What both layouts of ChainEstimator share (detail::PerDofChain, detail::LaneChain): the
/// configuration phase, the boundary, the sample check, and the accessors derived from the
/// layout's own (`update(const Scalar*, const Scalar*)`, `valid()`, `samples()`).

#include "algid/chain_config.hpp"
#include "algid/types.hpp"

#include <cmath>

namespace algid {
namespace detail {

/// CRTP base of a chain layout `Derived` of N DOF with P-point quadrature.
template <class Derived, int N, class Scalar, int P>
class ChainCommon {
 public:
  using Config = ChainConfig<Scalar>;
  /// Samples by which the estimates lag the newest sample.
  static constexpr int kDelay = P - 2;
  /// Number of DOF.
  static constexpr int kDofs = N;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ConfigError validate(const Config& config) noexcept { return algid::validate(config); }

  /// Same as update(const Scalar*, const Scalar*) for Eigen vectors.
  /// @realtime no allocation, no throw
  Status update(const Vector<Scalar, N>& accel, const Vector<Scalar, N>& force) noexcept {
    return self().update(accel.data(), force.data());
  }

  /// True when every DOF is valid.
  bool all_valid() const noexcept {
    for (bool v : self().valid())
      if (!v) return false;
    return true;
  }
  /// Window length t_k - delay h - t0 [s] that the current estimates describe (0 before).
  Scalar window() const noexcept {
    const long samples = self().samples();
    return samples >= P ? static_cast<Scalar>(samples - P + 1) * config_.dt : Scalar(0);
  }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 protected:
  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit ChainCommon(const Config& config) : config_(config) {
    const ConfigError e = validate(config);
    if (e != ConfigError::kNone) config_error(to_string(e));
  }

  bool free_end() const noexcept { return config_.boundary == Boundary::kFree; }
  /// The last DOF solves a 3x3 system: a free right end, or N = 1 with walls (k_1 + k_2).
  bool reduced_last() const noexcept { return N == 1 || free_end(); }
  bool is_reduced(int i) const noexcept { return i == N - 1 && reduced_last(); }

  /// True when the first `count` accelerations and forces (one sample: N) are all finite.
  static bool finite(const Scalar* accel, const Scalar* force, int count = N) noexcept {
    bool ok = true;
    for (int e = 0; e < count; ++e) ok &= std::isfinite(accel[e]) & std::isfinite(force[e]);
    return ok;
  }

  Config config_;

 private:
  const Derived& self() const noexcept { return static_cast<const Derived&>(*this); }
  Derived& self() noexcept { return static_cast<Derived&>(*this); }
};

}  // namespace detail
}  // namespace algid
