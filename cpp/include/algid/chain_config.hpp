#pragma once
/// @file chain_config.hpp
/// Configuration of a ChainEstimator and its validation (the configuration phase).

#include "algid/algebraic_system.hpp"
#include "algid/types.hpp"

#include <cmath>

namespace algid {

/// Configuration of a ChainEstimator.
template <class Scalar>
struct ChainConfig {
  Scalar dt = Scalar(1e-3);              ///< sample period [s]
  Boundary boundary = Boundary::kFixed;  ///< right end: wall (k_{n+1} estimated) or free (k_{n+1} = 0)
  ValidityRule<Scalar> validity{};       ///< when an instantaneous solution is trusted
};

/// Why a configuration is rejected (kNone: accepted).
enum class ConfigError { kNone, kBadSamplePeriod, kBadMinSamples, kBadMinHadamard, kBadDofs };

/// Human-readable text of a ConfigError.
inline const char* to_string(ConfigError e) noexcept {
  switch (e) {
    case ConfigError::kNone: return "ok";
    case ConfigError::kBadSamplePeriod: return "dt must be in [1e-9, 3600] s (1 GHz to one sample an hour)";
    case ConfigError::kBadMinSamples: return "validity.min_samples must be >= 1";
    case ConfigError::kBadMinHadamard: return "validity.min_hadamard must be in [0, 1)";
    case ConfigError::kBadDofs: return "the number of DOF must be >= 1 (and equal N for a fixed-size estimator)";
  }
  return "unknown";
}

/// Check a configuration without side effects. @realtime no allocation, no throw
template <class Scalar>
ConfigError validate(const ChainConfig<Scalar>& config) noexcept {
  if (!(config.dt >= Scalar(1e-9) && config.dt <= Scalar(3600))) return ConfigError::kBadSamplePeriod;
  if (config.validity.min_samples < 1) return ConfigError::kBadMinSamples;
  if (!(config.validity.min_hadamard >= Scalar(0) && config.validity.min_hadamard < Scalar(1)))
    return ConfigError::kBadMinHadamard;
  return ConfigError::kNone;
}

}  // namespace algid
