#pragma once
/// @file weak_form_source.hpp
/// Weak-form windows as a window source of the continuous estimator (the default): the
/// WeakFormWindows of `window_s` (GLS over all test-function rows, bias-compensated, no
/// prefilter: the test functions are the low-pass, and a prefilter would colour the noise the
/// weights and the bias correction assume white), and with `joint` a second, longer set of
/// `long_window_s` with as many test functions. Every short window result goes to the tracks;
/// both kinds of window join their JointSums (joint_sum.hpp).
///
/// Storage: the windows' buffers, sized by the window and the band (about 0.3 MB for n = 5),
/// allocated by the constructor for every N: firmware without a heap runs AlgebraicWindows.

#include "algid/chain_config.hpp"
#include "algid/continuous_error.hpp"
#include "algid/joint_sum.hpp"
#include "algid/types.hpp"
#include "algid/weak_form.hpp"

#include <cmath>
#include <memory>

namespace algid {

/// Configuration of WeakFormSource (and of its JointSums).
template <class Scalar>
struct WeakFormSourceConfig : JointConfig<Scalar> {
  Scalar dt = Scalar(1e-3);              ///< sample period [s]
  Boundary boundary = Boundary::kFixed;  ///< right end: wall or free (see ChainEstimator)
  Scalar window_s = Scalar(0.5);         ///< window length W [s] (rounded to a multiple of K samples)
  int stagger = 4;                       ///< windows in flight K, started W/K apart (<= MaxStagger)
  /// independent fraction of the staggered window results, (0, 1]. Successive weak-form results
  /// are more correlated than algebraic ones (sin^4 taper, K = 4): larger values raised CUSUM
  /// false alarms on dampings (docs/continuous.md, defaults).
  Scalar overlap_efficiency = Scalar(0.25);
  Scalar band_hz = Scalar(-1);      ///< highest test-function frequency [Hz]; -1: 0.05 / dt
  Scalar accel_noise = Scalar(-1);  ///< acceleration noise RMS [m/s^2]; -1: estimated
  Scalar force_noise = Scalar(-1);  ///< force noise RMS [N]; -1: estimated
  bool bias_compensation = true;    ///< subtract the regressor-noise term
  bool gls = true;                  ///< rows weighted by their noise covariance (false: unweighted)
  /// with `joint`: length [s] of a second, longer set of windows with a joint sum of its own,
  /// with as many test functions as the others (so their band is band_hz window_s /
  /// long_window_s); each parameter is reported from the joint sum (short or long windows) with
  /// the smaller uncertainty (long windows resolve the resonances more finely: closer to the
  /// Cramer-Rao bound on the dampings); -1: three times window_s; 0: none
  Scalar long_window_s = Scalar(-1);
};

/// The weak-form window source (see the file comment).
/// @tparam N number of DOF, or Dynamic. @tparam MaxStagger most windows in flight.
template <int N, class Scalar = double, int MaxStagger = 4>
class WeakFormSource {
 public:
  /// The windows of either length.
  using Windows = WeakFormWindows<N, Scalar, MaxStagger>;
  /// Configuration type.
  using Config = WeakFormSourceConfig<Scalar>;
  /// Scalar type of the samples and results.
  using ScalarType = Scalar;
  /// The aggregation of these windows' information.
  using Joints = JointSums<Scalar>;
  /// Number of DOF (Dynamic: given to the constructor).
  static constexpr int kDofs = N;
  /// Number of parameters of a window result (Dynamic: 3n+1).
  static constexpr int kParams = N == Dynamic ? Dynamic : 3 * N + 1;
  /// Most windows in flight.
  static constexpr int kMaxStagger = MaxStagger;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ContinuousConfigError validate(const Config& c, int n = N) noexcept {
    ChainConfig<Scalar> chain;
    chain.dt = c.dt;
    chain.boundary = c.boundary;
    ContinuousConfigError e = continuous_error(algid::validate(chain, n));
    if (e != ContinuousConfigError::kNone) return e;
    if (N != Dynamic && n != N) return ContinuousConfigError::kBadDofs;
    e = continuous_error(Windows::validate(windows_config(c), n));
    if (e != ContinuousConfigError::kNone) return e;
    if (!(c.overlap_efficiency > Scalar(0) && c.overlap_efficiency <= Scalar(1)) ||
        !(c.joint_efficiency > Scalar(0) && c.joint_efficiency <= Scalar(1)))
      return ContinuousConfigError::kBadEfficiency;
    if (c.long_window_s != Scalar(-1) && !(c.long_window_s >= Scalar(0))) return ContinuousConfigError::kBadLongWindow;
    if (c.joint && long_window(c) > Scalar(0) && Windows::validate(long_config(c), n) != WeakFormConfigError::kNone)
      return ContinuousConfigError::kBadLongWindow;
    if (!std::isfinite(c.misfit_ratio) || (c.misfit_ratio != Scalar(0) && !(c.misfit_ratio > Scalar(1))))
      return ContinuousConfigError::kBadMisfitRatio;
    return ContinuousConfigError::kNone;
  }

  /// Configure (the configuration must be valid: see validate()). Allocates every buffer.
  WeakFormSource(const Config& config, int n) : config_(config) {
    short_ = std::make_unique<Windows>(windows_config(config_), n);
    config_.long_window_s = config_.joint ? long_window(config_) : Scalar(0);
    if (config_.long_window_s > Scalar(0)) long_ = std::make_unique<Windows>(long_config(config_), n);
  }

  /// The joint sums of these windows (none without `joint`). Allocates.
  Joints joints(int params, int block, Scalar horizon_s, bool amortize) const {
    return Joints(config_, params, short_->hop_samples(), long_ ? long_->hop_samples() : 0, block, config_.stagger,
                  horizon_s, config_.dt, amortize);
  }

  /// Drop the windows in flight; weights and noise estimates are kept. @realtime no allocation, no throw
  void restart() noexcept {
    short_->restart();
    if (long_) long_->restart();
  }

  /// Forget everything. @realtime no allocation, no throw
  void reset() noexcept {
    restart();
    short_->reset();
    if (long_) long_->reset();
  }

  /// Consume one screened sample [m/s^2, N]: the weights follow `sink.model()` (the running
  /// estimate); a short window result goes to `sink.window(result, variance)` and then to
  /// `sink.joint(0, windows)`, a fully weighted long one to `sink.joint(1, windows)`.
  /// @realtime no allocation, no throw
  template <class Sink>
  void update(const Scalar* accel, const Scalar* force, Sink& sink) noexcept {
    short_->set_model(sink.model());
    if (short_->update(accel, force)) {
      sink.window(short_->result(), short_->variance());
      sink.joint(0, *short_);
    }
    if (long_) {
      long_->set_model(sink.model());
      // fully weighted windows only: their summed information compares with the short sum's
      if (long_->update(accel, force) && long_->result_fully_weighted()) sink.joint(1, *long_);
    }
  }

  /// Window length [samples].
  long window_samples() const noexcept { return short_->window_samples(); }
  /// Samples between two window results.
  long hop_samples() const noexcept { return short_->hop_samples(); }
  /// Fewest samples between two window results.
  long min_spacing() const noexcept { return short_->hop_samples(); }
  /// Samples skipped after a (re)start: none (no prefilter).
  long settle_samples() const noexcept { return 0; }
  /// Prefilter cut-off: 0, none.
  Scalar prefilter_hz() const noexcept { return Scalar(0); }
  /// Estimated (or given) noise RMS of channel c: accelerations 0..n-1, forces n..2n-1.
  Scalar noise_rms(int c) const noexcept { return short_->noise_rms(c); }
  /// Misfit of the latest short window (NaN before a weighted one).
  double misfit() const noexcept { return short_->misfit(); }
  /// The short windows (those of the tracks, the change detector and the short joint sum).
  const Windows& short_windows() const noexcept { return *short_; }
  /// The long windows (nullptr without them).
  const Windows* long_windows() const noexcept { return long_.get(); }
  /// The configuration in force (long_window_s resolved: 0 without long windows).
  const Config& config() const noexcept { return config_; }

 private:
  static Scalar long_window(const Config& c) noexcept {
    return c.long_window_s == Scalar(-1) ? Scalar(3) * c.window_s : c.long_window_s;
  }

  static typename Windows::Config windows_config(const Config& c) noexcept {
    typename Windows::Config w;
    w.dt = c.dt;
    w.boundary = c.boundary;
    w.window_s = c.window_s;
    w.stagger = c.stagger;
    w.band_hz = c.band_hz;
    w.accel_noise = c.accel_noise;
    w.force_noise = c.force_noise;
    w.bias_compensation = c.bias_compensation;
    w.weighted = c.gls;
    return w;
  }

  // The long windows: as the short ones, long_window(c) long, with as many test functions
  // (F = 2 band W + 1): the same cost per window and per sample, a finer resolution in
  // frequency over a lower band (where the band matters, the short sum's variance is the smaller).
  static typename Windows::Config long_config(const Config& c) noexcept {
    typename Windows::Config w = windows_config(c);
    w.window_s = long_window(c);
    w.band_hz = static_cast<Scalar>(Windows::band_of(w)) * c.window_s / w.window_s;
    return w;
  }

  Config config_;
  std::unique_ptr<Windows> short_;
  std::unique_ptr<Windows> long_;
};

}  // namespace algid
