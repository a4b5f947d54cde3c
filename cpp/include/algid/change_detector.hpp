#pragma once
/// @file change_detector.hpp
/// Change detection per parameter against the running estimate of its track:
///   - step test: an alarm when the median robust z-score of the last `confirm` window results
///     (2K+1 by default: more than the K windows that straddle a change, so a transient in
///     the straddling windows cannot raise it) exceeds `step_threshold`; the track restarts
///     from the results of that run that agree with the new level.
///   - drift test: a two-sided CUSUM of the block medians, standardised by the sigma of a block
///     median and clipped at `cusum_clip`, reference `cusum_reference`, alarm at
///     `cusum_threshold`; the track restarts from the last block.
/// Each alarm is a ChangeEvent (sample, parameter, kind, estimate before and after).
///
/// Storage: two CUSUM sums per parameter (inside the object for a fixed size).

#include "algid/continuous_error.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <algorithm>
#include <cmath>

namespace algid {

/// Kind of a change event.
enum class ChangeKind : int {
  kNone = 0,   ///< no change
  kStep = 1,   ///< step test: the latest window results disagree with the running estimate
  kDrift = 2,  ///< drift test: the CUSUM of block medians crossed its threshold
};

/// One change event: the aggregation of parameter `param` was restarted.
template <class Scalar>
struct ChangeEvent {
  long sample = -1;                     ///< index of the sample whose update raised it (0-based)
  int param = -1;                       ///< parameter index: m_i = i, c_i = n + i, k_j = 2n + j (0-based)
  ChangeKind kind = ChangeKind::kNone;  ///< which test fired
  Scalar before = Scalar(0);            ///< running estimate before the restart [parameter units]
  Scalar after = Scalar(0);             ///< running estimate right after it [parameter units]
};

/// Configuration of the ChangeDetector.
template <class Scalar>
struct DetectorConfig {
  bool detect = true;                      ///< run the change detector
  int confirm = 0;                         ///< window results in the step test; 0: 2K+1 (<= Capacity)
  Scalar step_threshold = Scalar(6);       ///< step test: |median z| above this [per-window sigmas]
  Scalar cusum_reference = Scalar(0.75);   ///< drift test: CUSUM reference k [block-median sigmas]
  Scalar cusum_threshold = Scalar(5);      ///< drift test: alarm level h [block-median sigmas]
  Scalar cusum_clip = Scalar(4);           ///< drift test: clip of one standardised block median

  /// Check the fields for a ring of `capacity`. @realtime no allocation, no throw
  ContinuousConfigError validate(int capacity) const noexcept {
    if (confirm < 0 || confirm > capacity) return ContinuousConfigError::kBadConfirm;
    if (!(step_threshold > Scalar(0)) || !(cusum_threshold > Scalar(0)) || !(cusum_clip > Scalar(0)) ||
        !(cusum_reference >= Scalar(0)) || !std::isfinite(step_threshold) || !std::isfinite(cusum_threshold) ||
        !std::isfinite(cusum_clip) || !std::isfinite(cusum_reference))
      return ContinuousConfigError::kBadThreshold;
    return ContinuousConfigError::kNone;
  }
};

/// The step and drift tests of every parameter (see the file comment).
/// @tparam Params parameters (Dynamic: given to configure()).
template <class Scalar, int Params>
class ChangeDetector {
 public:
  /// Configuration type.
  using Config = DetectorConfig<Scalar>;

  /// Size and configure for K = `stagger` windows in flight and rings of `capacity`.
  void configure(int params, const Config& config, int stagger, int capacity) {
    config_ = config;
    confirm_ = config.confirm > 0 ? config.confirm : std::min(2 * stagger + 1, capacity);
    hi_.resize(params);
    lo_.resize(params);
    reset();
  }

  /// Zero every CUSUM. @realtime no allocation, no throw
  void reset() noexcept {
    hi_.fill(Scalar(0));
    lo_.fill(Scalar(0));
  }

  /// True if the tests run.
  bool enabled() const noexcept { return config_.detect; }
  /// Window results in the step test (config.confirm, or 2K+1).
  int confirm() const noexcept { return confirm_; }
  /// The step test's threshold [per-window sigmas].
  Scalar step_threshold() const noexcept { return config_.step_threshold; }

  /// Step test on the median z-score of the newest `confirm()` results.
  bool step(Scalar median_z) const noexcept { return std::abs(median_z) > config_.step_threshold; }

  /// Drift test of parameter j on a block median's deviation from the estimate `d` [block-median
  /// sigmas]; true on an alarm. @realtime no allocation, no throw
  bool drift(int j, Scalar d) noexcept {
    d = std::clamp(d, -config_.cusum_clip, config_.cusum_clip);
    hi_[j] = std::max(Scalar(0), hi_[j] + d - config_.cusum_reference);
    lo_[j] = std::max(Scalar(0), lo_[j] - d - config_.cusum_reference);
    return hi_[j] > config_.cusum_threshold || lo_[j] > config_.cusum_threshold;
  }

  /// Parameter j restarted: its CUSUM starts again. @realtime no allocation, no throw
  void clear(int j) noexcept { hi_[j] = lo_[j] = Scalar(0); }

 private:
  Config config_{};
  int confirm_ = 1;
  detail::Storage<Scalar, Params> hi_{}, lo_{};
};

}  // namespace algid
