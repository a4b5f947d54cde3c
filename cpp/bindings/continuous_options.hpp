#pragma once
// The Python ContinuousConfig: the window method chosen at run time and the configurations of
// both compiled estimators (WeakFormContinuousEstimator, AlgebraicContinuousEstimator), whose
// defaults it starts from. A field both have is written to both; `window_s` and
// `overlap_efficiency` keep -1 for "the method's default" (0.5 s / 0.3 s, 0.25 / 0.5).
#include <algid/algid.hpp>

#include <string>
#include <type_traits>

namespace algid_bindings {

/// The two compiled continuous estimators of a run-time sized chain.
using WeakFormContinuous = algid::WeakFormContinuousEstimator<algid::Dynamic, double>;
using AlgebraicContinuous = algid::AlgebraicContinuousEstimator<algid::Dynamic, double>;

struct ContinuousOptions {
  bool algebraic = false;             // the method: weak form (false) or algebraic windows (true)
  double window_s = -1;               // -1: the method's default
  double overlap_efficiency = -1;     // -1: the method's default
  WeakFormContinuous::Config weak{};  // the weak-form estimator's configuration
  AlgebraicContinuous::Config algebraic_config{};  // the algebraic estimator's configuration

  /// The configuration of the estimator `Est` (one of the two above).
  template <class Est>
  typename Est::Config config() const {
    typename Est::Config c;
    if constexpr (std::is_same_v<Est, WeakFormContinuous>) {
      c = weak;
    } else {
      c = algebraic_config;
    }
    if (window_s != -1) c.window_s = window_s;
    if (overlap_efficiency != -1) c.overlap_efficiency = overlap_efficiency;
    return c;
  }

  /// 'ok', or why a chain of n DOF rejects these options under their method.
  std::string validate(int n) const {
    return algebraic ? algid::to_string(AlgebraicContinuous::validate(config<AlgebraicContinuous>(), n))
                     : algid::to_string(WeakFormContinuous::validate(config<WeakFormContinuous>(), n));
  }
};

}  // namespace algid_bindings
