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
///
/// Layout. The arithmetic is the same for every N; how it is laid out in SIMD registers is
/// not. From three DOF on (detail::LaneChain) the DOF sit side by side, one per lane, and
/// every step of a sample advances 2, 4 or 8 of them at once; one or two DOF do not fill a
/// register, so there (detail::PerDofChain) each DOF is vectorised on its own and run()
/// solves 8 consecutive instants side by side instead. In both, run() leaves the estimator
/// after every sample exactly, to the bit, as update() would. The two layouts agree to
/// rounding (tests/cpp/test_estimator.cpp).
///
/// Interface (both layouts):
///   - `static ConfigError validate(const Config&)`, `explicit ChainEstimator(const Config&)`;
///   - `Status update(const Scalar* accel, const Scalar* force)` (N values each, [m/s^2], [N]),
///     `reseed()`, `long run(accel, force, T, observe)` (T x N row-major, `observe(t, status)`
///     after each sample), `long record(accel, force, T, histories)` (the estimates after
///     each sample written into caller-owned arrays: Histories, histories.hpp; the batch path
///     of the Python `run()`);
///   - `mass()`, `damping()` (N), `stiffness()` (N + 1: k_1 .. k_{N+1}, an interior spring the
///     mean of its two DOF's estimates; k_1 = k_1 + k_2 and k_2 NaN for N = 1 with walls,
///     k_{N+1} = 0 at a free end), `valid()`, `all_valid()`;
///   - per DOF i: `theta(i)` = eq. 7 [m_i, c_i, k_i, k_{i+1}], `theta_instant(i)` (the Cramer
///     solution of the last sample), `hadamard(i)`, `instant_valid(i)`;
///   - `samples()`, `window()` [s], `config()`, `kDelay`, `kDofs`.

#include "algid/chain_config.hpp"
#include "algid/detail/lane_chain.hpp"
#include "algid/detail/per_dof_chain.hpp"

#include <type_traits>

namespace algid {

/// Chains of at least this many DOF use the lane layout (detail::LaneChain).
inline constexpr int kLaneLayoutFrom = 3;

namespace detail {
template <int N, class Scalar, int P>
using ChainLayout = std::conditional_t<(N >= kLaneLayoutFrom), LaneChain<N, Scalar, P>, PerDofChain<N, Scalar, P>>;
}  // namespace detail

/// The estimator of an N-DOF chain; its interface is in the file comment.
/// @tparam N number of DOF (masses), >= 1.
/// @tparam Scalar double or float.
/// @tparam P quadrature points (even; 8 by default: O(h^8) chains, 6 samples of delay).
template <int N, class Scalar = double, int P = 8>
class ChainEstimator : public detail::ChainLayout<N, Scalar, P> {
  static_assert(N >= 1, "a chain has at least one DOF");
  using Layout = detail::ChainLayout<N, Scalar, P>;

 public:
  using Config = ChainConfig<Scalar>;
  /// True when the DOF are solved side by side in SIMD lanes (N >= kLaneLayoutFrom).
  static constexpr bool kLaneLayout = N >= kLaneLayoutFrom;

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit ChainEstimator(const Config& config) : Layout(config) {}
};

}  // namespace algid
