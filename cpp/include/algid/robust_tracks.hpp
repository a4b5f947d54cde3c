#pragma once
/// @file robust_tracks.hpp
/// Aggregation of window results per parameter (m_1..m_n, c_1..c_n, k_1..k_{n+1}). A window
/// result is heavy-tailed (a ratio of random determinants), so it goes through a median first:
/// the last `block` results form a block whose median enters a running mean of block medians
/// (close to Gaussian, so the mean is efficient; optional forgetting `horizon_s`). Until the
/// first block is complete the estimate is the median of the window results so far.
///
/// Uncertainty (one standard deviation, parameter units): the per-window spread 1.4826 MAD of
/// the ring, scaled to the block mean by sqrt(pi/2) / sqrt(blocks * block * overlap_efficiency)
/// (overlapping windows are not independent), or the observed scatter of the block medians if
/// larger (from 4 blocks on). It is the statistical spread only: the bias that noise on the
/// regressors causes is not in it.
///
/// Every result is scored against the estimate before it (z = (result - estimate) / the
/// floored spread, or the window's own sigma where larger) for the ChangeDetector; a restart
/// keeps the results that agree with the new level.
///
/// Storage: per parameter three rings of Capacity scalars (results, z-scores, the block's
/// window sigmas): 3 (3n+1) Capacity scalars, inside the object for a fixed size, allocated by
/// configure() for Dynamic.

#include "algid/continuous_error.hpp"
#include "algid/detail/robust.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace algid {

/// Configuration of the RobustTracks.
template <class Scalar>
struct TrackConfig {
  int block = 16;                              ///< window results per block median (<= Capacity)
  Scalar min_relative_spread = Scalar(1e-2);   ///< floor of the per-window spread relative to |estimate|
  int min_windows = 8;  ///< window results since a restart before the spread is trusted and the tests armed
  Scalar horizon_s = Scalar(0);  ///< forgetting time constant of the block mean [s]; 0: none

  /// Check the fields for a ring of `capacity`. @realtime no allocation, no throw
  ContinuousConfigError validate(int capacity) const noexcept {
    if (block < 1 || block > capacity) return ContinuousConfigError::kBadBlock;
    if (!(min_relative_spread >= Scalar(0)) || !std::isfinite(min_relative_spread))
      return ContinuousConfigError::kBadSpreadFloor;
    if (min_windows < 3 || min_windows > capacity) return ContinuousConfigError::kBadMinWindows;
    if (!(horizon_s >= Scalar(0)) || !std::isfinite(horizon_s)) return ContinuousConfigError::kBadHorizon;
    return ContinuousConfigError::kNone;
  }
};

/// The robust per-parameter tracks of a stream of window results (see the file comment).
/// @tparam Params parameters (Dynamic: given to configure()). @tparam Capacity ring length.
template <class Scalar, int Params, int Capacity>
class RobustTracks {
  static_assert(Capacity >= 3, "the ring must hold a median and a MAD");

 public:
  /// Configuration type.
  using Config = TrackConfig<Scalar>;

  /// Size and configure: results arrive `hop_s` [s] apart (a block spans `block` of them) and
  /// are independent by `overlap_efficiency`. Allocates for Params = Dynamic.
  void configure(int params, const Config& config, long window_samples, int stagger, Scalar dt,
                 Scalar overlap_efficiency) {
    config_ = config;
    params_ = params;
    overlap_efficiency_ = overlap_efficiency;
    tracks_.resize(params);
    estimate_.setZero(params);
    sigma_.setZero(params);
    const Scalar block_s = static_cast<Scalar>(config_.block) * static_cast<Scalar>(window_samples) /
                           static_cast<Scalar>(stagger) * dt;
    forget_ = config_.horizon_s > Scalar(0) ? std::exp(-block_s / config_.horizon_s) : Scalar(1);
    block_scale_ = detail::kMedianInefficiency<Scalar> /
                   std::sqrt(static_cast<Scalar>(config_.block) * overlap_efficiency);
  }

  /// Empty every track; the estimates and sigmas start at the given values. @realtime no allocation, no throw
  template <class V>
  void reset(const V& estimate, const V& sigma) noexcept {
    for (int j = 0; j < params_; ++j) tracks_[j] = Track{};
    estimate_ = estimate;
    sigma_ = sigma;
  }

  /// Result x of parameter j, of variance `variance` (NaN: unknown), joins its ring, scored
  /// against the estimate; returns the window's sigma (0: unknown). @realtime no allocation, no throw
  Scalar add(int j, Scalar x, Scalar variance) noexcept {
    Track& t = tracks_[j];
    const Scalar est = estimate_(j);
    // The window's own sigma (weak form with GLS weights), where it exceeds the track's
    // spread: a window in a lull of the excitation is uncertain, and says so.
    const Scalar sd = std::isfinite(variance) && variance > Scalar(0) ? std::sqrt(variance) : Scalar(0);
    Scalar z = std::numeric_limits<Scalar>::quiet_NaN();
    if (t.spread_ok && std::isfinite(est)) {
      const Scalar s = std::max(floor_spread(t, est), sd);
      if (s > Scalar(0)) z = (x - est) / s;
    }
    t.value[static_cast<std::size_t>(t.head)] = x;
    t.z[static_cast<std::size_t>(t.head)] = z;
    t.head = (t.head + 1) % Capacity;
    t.count = std::min(t.count + 1, Capacity);
    t.z_count = std::isfinite(z) ? std::min(t.z_count + 1, Capacity) : 0;
    ++t.since;
    ++t.fresh;
    return sd;
  }

  /// True if parameter j's newest `count` results are scored and min_windows have arrived since its restart.
  bool scored(int j, int count) const noexcept {
    const Track& t = tracks_[j];
    return t.since >= config_.min_windows && t.z_count >= count;
  }

  /// Median z-score of parameter j's newest `count` results. @realtime no allocation, no throw
  Scalar median_z(int j, int count) noexcept {
    newest(tracks_[j].z, tracks_[j].head, count);
    return detail::median_inplace(scratch_.data(), count);
  }

  /// The window sigma `sd` joins parameter j's block; true when the block is complete, with its
  /// median result in `median`. @realtime no allocation, no throw
  bool close_block(int j, Scalar sd, Scalar& median) noexcept {
    Track& t = tracks_[j];
    t.block_sd[static_cast<std::size_t>(t.in_block)] = sd;
    if (++t.in_block < config_.block) return false;
    t.in_block = 0;
    newest(t.value, t.head, config_.block);
    median = detail::median_inplace(scratch_.data(), config_.block);
    return true;
  }

  /// Sigma of a block median of parameter j, from the larger of the floored spread and the
  /// block's median window sigma; 0 until a block mean and a trusted spread exist.
  Scalar block_sigma(int j) noexcept {
    const Track& t = tracks_[j];
    if (!(t.s0 > Scalar(0) && t.spread_ok)) return Scalar(0);
    std::copy(t.block_sd.begin(), t.block_sd.begin() + config_.block, scratch_.begin());
    const Scalar block_sd = detail::median_inplace(scratch_.data(), config_.block);
    return block_scale_ * std::max(floor_spread(t, estimate_(j)), block_sd);
  }

  /// A block median joins parameter j's running mean. @realtime no allocation, no throw
  void accumulate(int j, Scalar median) noexcept {
    Track& t = tracks_[j];
    t.s0 = forget_ * t.s0 + Scalar(1);
    t.s1 = forget_ * t.s1 + median;
    t.s2 = forget_ * t.s2 + median * median;
    t.s0sq = forget_ * forget_ * t.s0sq + Scalar(1);
  }

  /// Restart after a step to the level of median z `mz`: keep the newest `count` results that
  /// agree with it (same sign, beyond half `threshold`); the others are from before the change
  /// or straddle it. @realtime no allocation, no throw
  void restart_step(int j, Scalar mz, int count, Scalar threshold) noexcept {
    Track& t = tracks_[j];
    int kept = 0;
    for (int i = count - 1; i >= 0; --i) {  // oldest first into scratch_
      const std::size_t slot = static_cast<std::size_t>((t.head - 1 - i + Capacity) % Capacity);
      const Scalar zi = t.z[slot];
      if ((zi > Scalar(0)) == (mz > Scalar(0)) && std::abs(zi) > Scalar(0.5) * threshold)
        scratch_[static_cast<std::size_t>(kept++)] = t.value[slot];
    }
    if (kept == 0)
      scratch_[static_cast<std::size_t>(kept++)] =
          t.value[static_cast<std::size_t>((t.head - 1 + Capacity) % Capacity)];
    for (int i = 0; i < kept; ++i) {
      const std::size_t slot = static_cast<std::size_t>((t.head - kept + i + Capacity) % Capacity);
      t.value[slot] = scratch_[static_cast<std::size_t>(i)];
    }
    t.count = kept;
    clear(t);
  }

  /// Restart after a drift: keep the block just completed. @realtime no allocation, no throw
  void restart_drift(int j) noexcept {
    Track& t = tracks_[j];
    t.count = std::min(t.count, config_.block);
    clear(t);
  }

  /// Spread, estimate and uncertainty of parameter j from its track. @realtime no allocation, no throw
  void refresh(int j) noexcept {
    Track& t = tracks_[j];
    // The per-window spread is trusted (and the tests armed) once min_windows results have
    // arrived: a MAD of three heavy-tailed values can be tiny. Before that a provisional spread
    // only feeds the uncertainty. After a restart the ring mixes two levels, so the relative
    // spread is carried until min_windows new results have arrived.
    const bool measure = t.fresh >= config_.min_windows;
    Scalar ring_median = std::numeric_limits<Scalar>::quiet_NaN();
    if (t.count >= 3 && (measure || !t.spread_ok)) {
      newest(t.value, t.head, t.count);
      ring_median = detail::median_inplace(scratch_.data(), t.count);
      t.spread = detail::kMadToSigma<Scalar> * detail::mad_inplace(scratch_.data(), t.count, ring_median);
      if (measure) {
        t.spread_ok = true;
        t.relative_spread = ring_median != Scalar(0) ? t.spread / std::abs(ring_median) : Scalar(0);
      }
    }
    Scalar est;
    if (t.s0 > Scalar(0)) {
      est = t.s1 / t.s0;
    } else {
      if (!std::isfinite(ring_median)) {
        newest(t.value, t.head, t.count);
        ring_median = detail::median_inplace(scratch_.data(), t.count);
      }
      est = ring_median;
    }
    if (!measure && t.spread_ok) t.spread = t.relative_spread * std::abs(est);
    Scalar sig;
    if (t.s0 > Scalar(0)) {
      const Scalar n_eff = t.s0 * t.s0 / t.s0sq;
      sig = block_scale_ * t.spread / std::sqrt(n_eff);
      if (n_eff >= Scalar(4)) {
        const Scalar var = (t.s2 / t.s0 - est * est) * n_eff / (n_eff - Scalar(1));
        sig = std::max(sig, std::sqrt(std::max(var, Scalar(0)) / n_eff));
      }
    } else {
      sig = detail::kMedianInefficiency<Scalar> * t.spread /
            std::sqrt(std::max(Scalar(1), static_cast<Scalar>(t.count) * overlap_efficiency_));
    }
    estimate_(j) = est;
    sigma_(j) = sig;
  }

  /// The tracks' estimates [parameter units].
  const Vector<Scalar, Params>& estimate() const noexcept { return estimate_; }
  /// Their one-sigma uncertainties [parameter units].
  const Vector<Scalar, Params>& sigma() const noexcept { return sigma_; }
  /// Window results aggregated into parameter j's estimate since its last restart.
  long since(int j) const noexcept { return tracks_[static_cast<std::size_t>(j)].since; }
  /// Per-window spread (1.4826 MAD of the ring) of parameter j [parameter units].
  Scalar spread(int j) const noexcept { return tracks_[static_cast<std::size_t>(j)].spread; }

 private:
  struct Track {
    std::array<Scalar, Capacity> value{};  // window results since the restart, newest at head - 1
    std::array<Scalar, Capacity> z{};  // their z-scores against the estimate before them
    int head = 0;
    int count = 0;  // entries since the restart, <= Capacity
    int z_count = 0;  // consecutive newest entries with a finite z, <= Capacity
    long since = 0;  // window results aggregated since the restart (kept ones included)
    long fresh = 0;  // window results that arrived after the restart
    int in_block = 0;  // results in the current block
    Scalar s0 = Scalar(0), s1 = Scalar(0), s2 = Scalar(0), s0sq = Scalar(0);  // block-statistic moments
    std::array<Scalar, Capacity> block_sd{};  // the current block's window sigmas (0: unknown)
    Scalar spread = std::numeric_limits<Scalar>::quiet_NaN();  // per-window sigma
    Scalar relative_spread = std::numeric_limits<Scalar>::quiet_NaN();  // carried over a restart
    bool spread_ok = false;  // spread measured on >= min_windows results: the tests may run
  };

  static void clear(Track& t) noexcept {
    t.since = t.count;
    t.fresh = 0;
    t.z_count = 0;
    t.in_block = 0;
    t.s0 = t.s1 = t.s2 = t.s0sq = Scalar(0);
  }

  // Copy the newest `count` entries of a ring into scratch_, newest last.
  void newest(const std::array<Scalar, Capacity>& ring, int head, int count) noexcept {
    for (int i = 0; i < count; ++i)
      scratch_[static_cast<std::size_t>(count - 1 - i)] =
          ring[static_cast<std::size_t>((head - 1 - i + Capacity) % Capacity)];
  }

  Scalar floor_spread(const Track& t, Scalar estimate) const noexcept {
    return std::max(t.spread, config_.min_relative_spread * std::abs(estimate));
  }

  Config config_{};
  int params_ = 0;
  Scalar overlap_efficiency_ = Scalar(1);
  Scalar forget_ = Scalar(1);
  Scalar block_scale_ = Scalar(1);
  detail::Storage<Track, Params> tracks_{};
  std::array<Scalar, Capacity> scratch_{};
  Vector<Scalar, Params> estimate_, sigma_;
};

}  // namespace algid
