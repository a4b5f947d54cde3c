#pragma once
/// @file chain_common.hpp
/// What both layouts of ChainEstimator share (detail::PerDofChain, detail::LaneChain): the
/// configuration phase, the boundary, the sample check, and the accessors derived from the
/// layout's own (`update(const Scalar*, const Scalar*)`, `run()`, the accessors), and
/// record() where the layout has no faster one.

#include "algid/chain_config.hpp"
#include "algid/histories.hpp"
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

  /// Consume a record of T samples (T x N, row-major, as run()) and write the estimates after
  /// each sample into row t of `out` (see Histories): what run() with an observer that copies
  /// the accessors writes, to the bit. Returns what run() returns.
  /// @realtime no allocation, no throw
  long record(const Scalar* accel, const Scalar* force, long T, const Histories<Scalar>& out) noexcept {
    return self().run(accel, force, T, [&](long t, Status s) { write_row(t, s, out); });
  }

  /// Write row t of `out` (see Histories) from the accessors, after a sample of status `s`:
  /// what record() writes after sample t. @realtime no allocation, no throw
  void write_row(long t, Status s, const Histories<Scalar>& out) const noexcept {
    const Derived& d = self();
    out.status[t] = static_cast<std::int8_t>(s);
    for (int i = 0; i < N; ++i) {
      out.mass[t * N + i] = d.mass()(i);
      out.damping[t * N + i] = d.damping()(i);
      out.valid[t * N + i] = d.valid()[static_cast<std::size_t>(i)];
    }
    for (int j = 0; j <= N; ++j) out.stiffness[t * (N + 1) + j] = d.stiffness()(j);
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
