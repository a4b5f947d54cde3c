#pragma once
/// @file continuous_error.hpp
/// Why a continuous estimator's configuration is rejected: one enum for every concept of it
/// (input screen, window source, tracks, change detector, joint sums).

#include "algid/chain_config.hpp"
#include "algid/weak_form.hpp"

namespace algid {

/// Why a ContinuousConfig is rejected (kNone: accepted).
enum class ContinuousConfigError {
  kNone,
  kBadSamplePeriod,
  kBadMinSamples,
  kBadMinHadamard,
  kBadWindow,
  kBadStagger,
  kBadBlock,
  kBadConfirm,
  kBadThreshold,
  kBadSpreadFloor,
  kBadMinWindows,
  kBadEfficiency,
  kBadHorizon,
  kBadPrefilter,
  kBadOutlierRatio,
  kBadMisfitRatio,
  kBadDropout,
  kBadDofs,
  kBadBand,
  kBadNoise,
  kBadLongWindow,
};

/// Human-readable text of a ContinuousConfigError.
inline const char* to_string(ContinuousConfigError e) noexcept {
  switch (e) {
    case ContinuousConfigError::kNone: return "ok";
    case ContinuousConfigError::kBadSamplePeriod: return to_string(ConfigError::kBadSamplePeriod);
    case ContinuousConfigError::kBadMinSamples: return "validity.min_samples must be >= 1";
    case ContinuousConfigError::kBadMinHadamard: return "validity.min_hadamard must be in [0, 1)";
    case ContinuousConfigError::kBadWindow:
      return "window_s must be finite and hold P + validity.min_samples to 1e7 samples";
    case ContinuousConfigError::kBadStagger: return "stagger must be in [1, MaxStagger] and <= window samples";
    case ContinuousConfigError::kBadBlock: return "block must be in [1, Capacity]";
    case ContinuousConfigError::kBadConfirm: return "confirm must be 0 (auto) or in [1, Capacity]";
    case ContinuousConfigError::kBadThreshold:
      return "step_threshold, cusum_threshold and cusum_clip must be > 0, cusum_reference >= 0";
    case ContinuousConfigError::kBadSpreadFloor: return "min_relative_spread must be finite and >= 0";
    case ContinuousConfigError::kBadMinWindows: return "min_windows must be in [3, Capacity]";
    case ContinuousConfigError::kBadEfficiency:
      return "overlap_efficiency must be in (0, 1], joint_efficiency in (0, 1]";
    case ContinuousConfigError::kBadHorizon: return "horizon_s must be finite and >= 0 [s]";
    case ContinuousConfigError::kBadPrefilter:
      return "prefilter_hz must be -1 (0.05/dt), 0 (off) or in [1e-6/dt, 0.45/dt) [Hz], prefilter_order 2 or 4";
    case ContinuousConfigError::kBadOutlierRatio: return "outlier_ratio must be 0 (off) or finite and > 1";
    case ContinuousConfigError::kBadMisfitRatio: return "misfit_ratio must be 0 (off) or finite and > 1";
    case ContinuousConfigError::kBadDropout: return "stuck_samples and clip_samples must be 0 (off) or >= 2";
    case ContinuousConfigError::kBadDofs: return to_string(ConfigError::kBadDofs);
    case ContinuousConfigError::kBadBand: return to_string(WeakFormConfigError::kBadBand);
    case ContinuousConfigError::kBadNoise: return to_string(WeakFormConfigError::kBadNoise);
    case ContinuousConfigError::kBadLongWindow:
      return "long_window_s must be -1 (three times window_s), 0 (none) or a window of at least 32 samples that holds "
             "the band (2 band_hz long_window_s + 1 <= its samples / 2)";
  }
  return "unknown";
}

/// The ContinuousConfigError of a ChainEstimator's ConfigError.
inline ContinuousConfigError continuous_error(ConfigError e) noexcept {
  switch (e) {
    case ConfigError::kNone: return ContinuousConfigError::kNone;
    case ConfigError::kBadSamplePeriod: return ContinuousConfigError::kBadSamplePeriod;
    case ConfigError::kBadMinSamples: return ContinuousConfigError::kBadMinSamples;
    case ConfigError::kBadMinHadamard: return ContinuousConfigError::kBadMinHadamard;
    case ConfigError::kBadDofs: return ContinuousConfigError::kBadDofs;
  }
  return ContinuousConfigError::kBadDofs;
}

/// The ContinuousConfigError of a WeakFormWindows' WeakFormConfigError.
inline ContinuousConfigError continuous_error(WeakFormConfigError e) noexcept {
  switch (e) {
    case WeakFormConfigError::kNone: return ContinuousConfigError::kNone;
    case WeakFormConfigError::kBadSamplePeriod: return ContinuousConfigError::kBadSamplePeriod;
    case WeakFormConfigError::kBadWindow: return ContinuousConfigError::kBadWindow;
    case WeakFormConfigError::kBadStagger: return ContinuousConfigError::kBadStagger;
    case WeakFormConfigError::kBadBand: return ContinuousConfigError::kBadBand;
    case WeakFormConfigError::kBadNoise: return ContinuousConfigError::kBadNoise;
    case WeakFormConfigError::kBadDofs: return ContinuousConfigError::kBadDofs;
  }
  return ContinuousConfigError::kBadDofs;
}

}  // namespace algid
