#pragma once
/// @file continuous_estimator.hpp
/// Continuous operation of the algebraic estimator: automatic reseeding, a running estimate
/// with an uncertainty per parameter, and a change detector.
///
/// Why: one growing window from t0 degrades under measurement noise (the iterated integrals
/// of the noise grow faster than the information), so the estimator is restarted on short
/// windows and the window results are aggregated.
///
/// Window results come from WeakFormWindows (weak_form.hpp, the default: GLS over all
/// weak-form rows of a 0.5 s window, bias-compensated, no prefilter) or, with
/// WindowMethod::kAlgebraic, from the pipeline below (steps 0-1). With weak-form windows the
/// reported estimate is the solution of the summed window normal equations (Joint, below); the
/// per-parameter aggregation of steps 2-3 still runs and drives the change detector (step 4),
/// and a restarted parameter is marginalised out of the joint sum (docs/continuous.md).
///
/// Pipeline of the algebraic windows, per sample:
///   0. Prefilter. The accelerations and the forces pass through the same Butterworth
///      low-pass (`prefilter_hz`, default fs/20; order 4). Eq. 1 is linear and time-invariant,
///      so the filtered signals obey it with the same parameters, while the white noise above
///      the cut-off, which biases the windows (noise in the regressors: -5 % on masses at
///      20 dB without it) and scatters them, is gone. The windows start once the filter's
///      start-up transient has decayed to 1e-6 (115 ms at 50 Hz).
///   1. Windows. K (`stagger`) ChainEstimators run side by side on windows of M samples
///      (`window_s`), started M/K samples apart; each is reseeded when its window is full,
///      so a window result arrives every M/K samples (K = 4, 0.3 s: every 75 ms). With a
///      force on some DOF only, a window scales the DOF without force through their springs
///      (ChainEstimator, "One force"): the prefilter keeps a force that is 0 exactly 0.
///   2. Aggregation, per parameter (m_1..m_n, c_1..c_n, k_1..k_{n+1}; interior springs fused
///      as in ChainEstimator). A window result is heavy-tailed (a ratio of random
///      determinants), so it goes through a median first: the last `block` results form a
///      block whose median enters a running mean of block medians (close to Gaussian, so
///      the mean is efficient; optional forgetting `horizon_s`). Until the first block is
///      complete the estimate is the median of the window results so far.
///   3. Uncertainty (one standard deviation, parameter units): the per-window spread
///      1.4826 MAD of the ring, scaled to the block mean by sqrt(pi/2) / sqrt(blocks * block *
///      `overlap_efficiency`) (overlapping windows are not independent), or the observed
///      scatter of the block medians if larger (from 4 blocks on). It is the statistical
///      spread only: the bias that noise on the regressors causes (after the prefilter about
///      -1 % on masses and springs at 20 dB SNR, -5 % without it) is not in it.
///   4. Change detection, per parameter, against the running estimate:
///      - step test: robust z = (result - estimate) / max(spread, `min_relative_spread` |estimate|,
///        the window's own sigma where the weak form's GLS gives one: a window in a lull of
///        the excitation is uncertain) of each window result; an alarm when the median z of the last `confirm` results
///        (2K+1 by default: more than the K windows that straddle a change, so a transient
///        in the straddling windows cannot raise it) exceeds `step_threshold`. The
///        aggregation restarts from the results of that run that agree with the new level.
///      - drift test: a two-sided CUSUM of the block medians (standardised by the spread of
///        a block median, from the larger of the floored spread and the block's median window
///        sigma, clipped at `cusum_clip`, reference `cusum_reference`, alarm at
///        `cusum_threshold`); the aggregation restarts from the last block.
///      Each alarm is a ChangeEvent (sample, parameter, kind, estimate before and after).
///
/// Real-time contract: construction validates the configuration and may throw
/// (std::invalid_argument; call `validate()` first where exceptions are off). `update()`,
/// `reset()` and every accessor are noexcept and allocate nothing. The per-parameter work of
/// a window result (two nth_element passes over at most Capacity values) is spread over the
/// samples until the next result (`amortize`), so no single sample pays for all 3n+1
/// parameters; the estimates therefore lag the window end by at most M/K samples. The weak
/// form's O((3n+1)^3) parts (a window's factorisation and its back-substitutions, the joint
/// system's factorisation and its solution with the inverse) each take a sample of their own.
///
/// Storage: MaxStagger ChainEstimator<N>, the prefilter (8 states per channel), and per
/// parameter three arrays of Capacity scalars (window results, their z-scores, the block's
/// window sigmas): 3 (3n+1) Capacity scalars: about 75 KiB for n = 3, 1.3 MiB for n = 64 (defaults). Inside the
/// object for a fixed N; allocated by the constructor for N = Dynamic (n given at run time).
/// The weak-form windows (WindowMethod::kWeakForm, the default) and their joint system add
/// buffers sized by the window and the band (about 0.3 MB for n = 5), allocated by the
/// constructor for every N: firmware without a heap uses WindowMethod::kAlgebraic.

#include "algid/chain_estimator.hpp"
#include "algid/detail/dropout.hpp"
#include "algid/detail/prefilter.hpp"
#include "algid/detail/robust.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"
#include "algid/weak_form.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <utility>

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
  long sample = -1;                       ///< index of the sample whose update raised it (0-based)
  int param = -1;                         ///< parameter index: m_i = i, c_i = n + i, k_j = 2n + j (0-based)
  ChangeKind kind = ChangeKind::kNone;    ///< which test fired
  Scalar before = Scalar(0);              ///< running estimate before the restart [parameter units]
  Scalar after = Scalar(0);               ///< running estimate right after it [parameter units]
};

/// Where the window results come from.
enum class WindowMethod : int {
  kWeakForm = 0,   ///< WeakFormWindows: GLS over all test-function rows, bias-compensated (default)
  kAlgebraic = 1,  ///< ChainEstimator: the paper's exactly determined windows behind the prefilter
};

/// Configuration of a ContinuousEstimator. The defaults are the ones benchmarked in
/// bench/continuous.py (1 kHz, broadband forcing, 20-60 dB SNR).
template <class Scalar>
struct ContinuousConfig {
  Scalar dt = Scalar(1e-3);                       ///< sample period [s]
  Boundary boundary = Boundary::kFixed;           ///< right end: wall or free (see ChainEstimator)
  ValidityRule<Scalar> validity{};                ///< validity rule of every window
  WindowMethod method = WindowMethod::kWeakForm;  ///< source of the window results
  Scalar window_s = Scalar(-1);  ///< window length L [s] (rounded to samples); -1: 0.5 (weak form), 0.3 (algebraic)
  int stagger = 4;                                ///< windows in flight K, started L/K apart (<= MaxStagger)
  int block = 16;                                 ///< window results per block median (<= Capacity)
  int confirm = 0;                                ///< window results in the step test; 0: 2K+1 (<= Capacity)
  Scalar step_threshold = Scalar(6);              ///< step test: |median z| above this [per-window sigmas]
  Scalar cusum_reference = Scalar(0.75);          ///< drift test: CUSUM reference k [block-median sigmas]
  Scalar cusum_threshold = Scalar(5);             ///< drift test: alarm level h [block-median sigmas]
  Scalar cusum_clip = Scalar(4);                  ///< drift test: clip of one standardised block median
  Scalar min_relative_spread = Scalar(1e-2);      ///< floor of the per-window spread relative to |estimate|
  int min_windows = 8;                            ///< window results since a restart before the tests are armed
  /// independent fraction of the staggered window results, (0, 1]; -1: 0.25 (weak form), 0.5 (algebraic)
  Scalar overlap_efficiency = Scalar(-1);
  /// weak form: sigma = sqrt(diag(N^-1) / joint_efficiency), for the overlap of the windows' information, (0, 1]
  Scalar joint_efficiency = Scalar(0.3);
  /// weak form with `joint`: length [s] of a second, longer set of weak-form windows with a
  /// joint sum of its own, with as many test functions as the others (so their band is
  /// band_hz window_s / long_window_s); each parameter is reported from the joint sum (short or
  /// long windows) with the smaller uncertainty (long windows resolve the resonances more
  /// finely: closer to the Cramer-Rao bound on the dampings); -1: three times window_s; 0: none
  Scalar long_window_s = Scalar(-1);
  Scalar horizon_s = Scalar(0);                   ///< forgetting time constant of the block mean [s]; 0: none
  Scalar prefilter_hz = Scalar(-1);  ///< low-pass on accelerations and forces alike [Hz]; -1: 0.05 / dt, 0: off
  int prefilter_order = 4;  ///< Butterworth order of the prefilter: 2 or 4
  Scalar band_hz = Scalar(-1);      ///< weak form: highest test-function frequency [Hz]; -1: 0.05 / dt
  Scalar accel_noise = Scalar(-1);  ///< weak form: acceleration noise RMS [m/s^2]; -1: estimated
  Scalar force_noise = Scalar(-1);  ///< weak form: force noise RMS [N]; -1: estimated
  bool bias_compensation = true;    ///< weak form: subtract the regressor-noise term
  bool gls = true;                  ///< weak form: rows weighted by their noise covariance (false: unweighted)
  bool joint = true;  ///< weak form: estimate from the summed window normal equations (false: block medians)
  bool detect = true;  ///< run the change detector
  bool amortize = true;  ///< spread the per-parameter work over the samples
  /// A finite sample beyond this many times its channel's running RMS (time constant one
  /// window, measured once a window of samples has passed) is treated as bad input; 0: off.
  Scalar outlier_ratio = Scalar(1e8);
  /// Weak form: a window whose misfit (WeakFormWindows::misfit(), the weighted residual per
  /// degree of freedom) exceeds this many times the larger of 1 and the median misfit of the
  /// 16 windows before it stays out of the joint normal equations (finite garbage, a transient
  /// the chain does not describe, a window straddling a change); the block medians and the
  /// change detector still see it. 0: off.
  Scalar misfit_ratio = Scalar(30);
  /// An acceleration that has moved and then repeats one value exactly for this many samples in
  /// a row is a dead sensor (detail/dropout.hpp): its samples are discarded like bad input and
  /// update() returns kDropout; 0: off. Short, because the windows harvested before a run is
  /// recognised keep its frozen samples (a2 frozen 2 s in tests/test_dropouts.py: masses and
  /// springs within 0.5 % with 16, 4.8 % off with 500).
  long stuck_samples = 16;
  /// An acceleration that repeats its largest or smallest value so far for this many samples in
  /// a row is clipped: discarded the same way; 0: off.
  long clip_samples = 3;
};

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
      return "overlap_efficiency must be -1 (auto) or in (0, 1], joint_efficiency in (0, 1]";
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

/// Continuous estimator of an N-DOF chain: staggered reseeded windows, robust running
/// estimate with uncertainty, change detection (see the file comment).
/// @tparam N number of DOF, >= 1, or Dynamic (given to the constructor).
/// @tparam Scalar double or float.
/// @tparam P quadrature points of the windows (see ChainEstimator).
/// @tparam Capacity window results kept per parameter (ring); bounds `block`, `confirm`.
/// @tparam MaxStagger most windows in flight (storage for MaxStagger ChainEstimators).
template <int N, class Scalar = double, int P = 8, int Capacity = 64, int MaxStagger = 4>
class ContinuousEstimator {
  static_assert(N >= 1 || N == Dynamic, "a chain has at least one DOF");
  static_assert(Capacity >= 3, "the ring must hold a median and a MAD");
  static_assert(MaxStagger >= 1, "at least one window");

 public:
  /// The estimator run on each window.
  using Window = ChainEstimator<N, Scalar, P>;
  /// The weak-form windows (WindowMethod::kWeakForm).
  using WeakForm = WeakFormWindows<N, Scalar, MaxStagger>;
  /// Configuration type.
  using Config = ContinuousConfig<Scalar>;
  /// Change event type.
  using Event = ChangeEvent<Scalar>;
  /// Number of DOF (Dynamic: see dofs()).
  static constexpr int kDofs = N;
  /// Number of reported parameters: m_1..m_N, c_1..c_N, k_1..k_{N+1} (Dynamic: see params()).
  static constexpr int kParams = N == Dynamic ? Dynamic : 3 * N + 1;
  /// Ring capacity per parameter [window results].
  static constexpr int kCapacity = Capacity;
  /// Most windows in flight.
  static constexpr int kMaxStagger = MaxStagger;
  /// Longest window [samples] (1e7: 2.8 h at 1 kHz).
  static constexpr long kMaxWindowSamples = 10000000;
  /// Lowest prefilter cut-off [cycles per sample] (1e-6: 1 mHz at 1 kHz; its start-up transient
  /// lasts about 6e6 samples).
  static constexpr double kMinPrefilterCycles = 1e-6;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ContinuousConfigError validate(const Config& c, int n = N) noexcept {
    switch (Window::validate(window_config(c), n)) {
      case ConfigError::kNone: break;
      case ConfigError::kBadSamplePeriod: return ContinuousConfigError::kBadSamplePeriod;
      case ConfigError::kBadMinSamples: return ContinuousConfigError::kBadMinSamples;
      case ConfigError::kBadMinHadamard: return ContinuousConfigError::kBadMinHadamard;
      case ConfigError::kBadDofs: return ContinuousConfigError::kBadDofs;
    }
    const Scalar window_s = resolved_window(c);
    if (!std::isfinite(window_s) || !(window_s > Scalar(0))) return ContinuousConfigError::kBadWindow;
    const Scalar samples = window_s / c.dt;
    if (!std::isfinite(samples) || samples > Scalar(kMaxWindowSamples)) return ContinuousConfigError::kBadWindow;
    const long m = std::lround(samples);
    if (m < static_cast<long>(P) + c.validity.min_samples) return ContinuousConfigError::kBadWindow;
    if (c.stagger < 1 || c.stagger > MaxStagger || c.stagger > m) return ContinuousConfigError::kBadStagger;
    if (c.block < 1 || c.block > Capacity) return ContinuousConfigError::kBadBlock;
    if (c.confirm < 0 || c.confirm > Capacity) return ContinuousConfigError::kBadConfirm;
    if (!(c.step_threshold > Scalar(0)) || !(c.cusum_threshold > Scalar(0)) || !(c.cusum_clip > Scalar(0)) ||
        !(c.cusum_reference >= Scalar(0)) || !std::isfinite(c.step_threshold) || !std::isfinite(c.cusum_threshold) ||
        !std::isfinite(c.cusum_clip) || !std::isfinite(c.cusum_reference))
      return ContinuousConfigError::kBadThreshold;
    if (!(c.min_relative_spread >= Scalar(0)) || !std::isfinite(c.min_relative_spread))
      return ContinuousConfigError::kBadSpreadFloor;
    if (c.min_windows < 3 || c.min_windows > Capacity) return ContinuousConfigError::kBadMinWindows;
    if ((!(c.overlap_efficiency > Scalar(0) && c.overlap_efficiency <= Scalar(1)) &&
         c.overlap_efficiency != Scalar(-1)) ||
        !(c.joint_efficiency > Scalar(0) && c.joint_efficiency <= Scalar(1)))
      return ContinuousConfigError::kBadEfficiency;
    if (!(c.horizon_s >= Scalar(0)) || !std::isfinite(c.horizon_s)) return ContinuousConfigError::kBadHorizon;
    if (!std::isfinite(c.prefilter_hz) || (c.prefilter_hz < Scalar(0) && c.prefilter_hz != Scalar(-1)) ||
        (c.prefilter_hz > Scalar(0) && !(c.prefilter_hz * c.dt >= Scalar(kMinPrefilterCycles))) ||
        !(c.prefilter_hz * c.dt < Scalar(0.45)) || (c.prefilter_order != 2 && c.prefilter_order != 4))
      return ContinuousConfigError::kBadPrefilter;
    if (c.method == WindowMethod::kWeakForm) {
      switch (WeakForm::validate(weak_config(c), n)) {
        case WeakFormConfigError::kNone: break;
        case WeakFormConfigError::kBadSamplePeriod: return ContinuousConfigError::kBadSamplePeriod;
        case WeakFormConfigError::kBadWindow: return ContinuousConfigError::kBadWindow;
        case WeakFormConfigError::kBadStagger: return ContinuousConfigError::kBadStagger;
        case WeakFormConfigError::kBadBand: return ContinuousConfigError::kBadBand;
        case WeakFormConfigError::kBadNoise: return ContinuousConfigError::kBadNoise;
        case WeakFormConfigError::kBadDofs: return ContinuousConfigError::kBadDofs;
      }
      if (c.long_window_s != Scalar(-1) && !(c.long_window_s >= Scalar(0)))
        return ContinuousConfigError::kBadLongWindow;
      if (c.joint && resolved_long_window(c) > Scalar(0) &&
          WeakForm::validate(long_config(c), n) != WeakFormConfigError::kNone)
        return ContinuousConfigError::kBadLongWindow;
    }
    if (!std::isfinite(c.outlier_ratio) || (c.outlier_ratio != Scalar(0) && !(c.outlier_ratio > Scalar(1))))
      return ContinuousConfigError::kBadOutlierRatio;
    if (!std::isfinite(c.misfit_ratio) || (c.misfit_ratio != Scalar(0) && !(c.misfit_ratio > Scalar(1))))
      return ContinuousConfigError::kBadMisfitRatio;
    if (c.stuck_samples < 0 || c.stuck_samples == 1 || c.clip_samples < 0 || c.clip_samples == 1)
      return ContinuousConfigError::kBadDropout;
    return ContinuousConfigError::kNone;
  }

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit ContinuousEstimator(const Config& config, int n = N)
      : config_(checked(config, n)),
        n_(detail::fixed_or<N>(n)),
        params_(3 * n_ + 1),
        windows_(make_windows(window_config(config), n_, std::make_index_sequence<MaxStagger>{})) {
    filter_.configure_channels(2 * n_);
    io_.resize(2 * n_);
    mean_square_.resize(2 * n_);
    mean_square_.fill(Scalar(0));
    known_.resize(params_);
    tracks_.resize(params_);
    events_.resize(params_);
    for (auto* v :
         {&estimate_, &sigma_, &last_window_, &last_variance_, &pending_, &pending_var_, &track_, &track_sigma_})
      v->setZero(params_);
    config_.window_s = resolved_window(config_);
    // Successive weak-form window results are more correlated (sin^4 taper, K = 4): CUSUM false
    // alarms on dampings with 0.5 (40 dB, tones) and 0.3 (20 dB, bench/continuous.py), none with 0.25.
    if (config_.overlap_efficiency == Scalar(-1))
      config_.overlap_efficiency = config_.method == WindowMethod::kWeakForm ? Scalar(0.25) : Scalar(0.5);
    weak_form_ = config_.method == WindowMethod::kWeakForm;
    window_samples_ = std::lround(config_.window_s / config_.dt);
    const Scalar fc = config_.prefilter_hz < Scalar(0) ? Scalar(0.05) / config_.dt : config_.prefilter_hz;
    if (weak_form_) {
      // The test functions are the low-pass; a prefilter would colour the noise the weights
      // and the bias correction assume white.
      weak_ = std::make_unique<WeakForm>(weak_config(config_), n_);
      window_samples_ = weak_->window_samples();
      if (config_.joint) {
        joint_ = make_joint(*weak_);
        config_.long_window_s = resolved_long_window(config_);
        if (config_.long_window_s > Scalar(0)) {
          long_ = std::make_unique<WeakForm>(long_config(config_), n_);
          long_joint_ = make_joint(*long_);
        }
      } else {
        config_.long_window_s = Scalar(0);
      }
    } else if (fc > Scalar(0)) {
      filter_.configure(fc, config_.dt, config_.prefilter_order);
      filtered_ = true;
      // ln(1e6) / decay: the start-up transient is below 1e-6 of the signal when windows start
      settle_ = static_cast<long>(std::ceil(Scalar(13.815510557964274) / filter_.decay() / config_.dt));
    }
    dropout_.configure(n_, config_.stuck_samples, config_.clip_samples);
    for (int e = 0; e < config_.stagger; ++e) offset_[e] = window_samples_ * e / config_.stagger;
    long spacing = window_samples_;  // fewest samples between two window results
    for (int e = 0; e < config_.stagger; ++e) {
      const long next = e + 1 < config_.stagger ? offset_[e + 1] : window_samples_ + offset_[0];
      spacing = std::min(spacing, next - offset_[e]);
    }
    budget_ = config_.amortize ? static_cast<int>((params_ + spacing - 1) / spacing) : params_;
    confirm_ = config_.confirm > 0 ? config_.confirm : std::min(2 * config_.stagger + 1, Capacity);
    const Scalar block_s = static_cast<Scalar>(config_.block) * static_cast<Scalar>(window_samples_) /
                           static_cast<Scalar>(config_.stagger) * config_.dt;
    forget_ = config_.horizon_s > Scalar(0) ? std::exp(-block_s / config_.horizon_s) : Scalar(1);
    block_scale_ = detail::kMedianInefficiency<Scalar> /
                   std::sqrt(static_cast<Scalar>(config_.block) * config_.overlap_efficiency);
    for (int j = 0; j < params_; ++j) known_[j] = Known::kEstimated;
    if (config_.boundary == Boundary::kFree) known_[params_ - 1] = Known::kZero;
    if (n_ == 1 && config_.boundary == Boundary::kFixed) known_[params_ - 1] = Known::kUnidentifiable;
    reset();
  }

  /// Forget everything (windows, aggregation, events); the next sample starts the schedule.
  /// @realtime no allocation, no throw
  void reset() noexcept {
    restart_windows();
    if (weak_) weak_->reset();
    if (long_) long_->reset();
    for (Joint* J : {joint_.get(), long_joint_.get()})
      if (J) J->clear();
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    for (int j = 0; j < params_; ++j) {
      tracks_[j] = Track{};
      const Scalar fixed = known_[j] == Known::kZero ? Scalar(0) : nan;
      estimate_(j) = fixed;
      sigma_(j) = known_[j] == Known::kZero ? Scalar(0) : nan;
      track_(j) = estimate_(j);
      track_sigma_(j) = sigma_(j);
      last_window_(j) = fixed;
      last_variance_(j) = nan;
      pending_(j) = nan;
      pending_var_(j) = nan;
    }
    pending_next_ = params_;
    mean_square_.fill(Scalar(0));
    accepted_ = 0;
    out_of_range_ = 0;
    dropout_.reset();
    dropout_samples_ = 0;
    dropout_runs_ = 0;
    last_dropout_ = Dropout::kNone;
    dropout_channel_ = -1;
    misfits_ = MisfitRing{};
    screened_ = 0;
    samples_ = 0;
    results_ = 0;
    event_count_ = 0;
    total_events_ = 0;
  }

  /// Consume one simultaneous sample of the accelerations [m/s^2] and forces [N].
  /// A sample plausible() refuses (not finite, not finite squared, or an outlier) is discarded
  /// and the windows in flight are dropped (the aggregation is kept): kBadInput. So is a sample
  /// in which an acceleration is stuck or clipped (`stuck_samples`, `clip_samples`): kDropout.
  /// Returns kWarmup until every identified parameter has an estimate.
  /// @realtime no allocation, no throw, O(K N) plus at most `budget` parameters' aggregation
  Status update(const Scalar* accel, const Scalar* force) noexcept {
    event_count_ = 0;
    ++samples_;
    if (!plausible(accel, force)) {
      restart_windows();
      work();
      return Status::kBadInput;
    }
    if (dropped(accel)) {
      restart_windows();
      work();
      return Status::kDropout;
    }
    const Scalar* a = accel;
    const Scalar* f = force;
    if (filtered_) {
      for (int i = 0; i < n_; ++i) {
        io_[i] = accel[i];
        io_[n_ + i] = force[i];
      }
      filter_.process(io_.data(), io_.data());  // cannot overflow: plausible() bounds |x| by sqrt(max)
      a = io_.data();
      f = io_.data() + n_;
    }
    if (weak_form_) {
      for (Joint* J : {joint_.get(), long_joint_.get()})
        if (J && J->stage != 0) joint_step(*J);
      weak_->set_model(estimate_.data());
      if (weak_->update(a, f)) {
        const bool joins = joint_ && fits(weak_->misfit());
        harvest(weak_->result(), weak_->variance());
        if (joins) joint_add(*joint_, *weak_);
      }
      if (long_) {
        long_->set_model(estimate_.data());
        // fully weighted windows only: their summed information compares with the short sum's
        if (long_->update(a, f) && long_->result_fully_weighted() && fits(long_->misfit()))
          joint_add(*long_joint_, *long_);
      }
      work();
      return ready() ? Status::kOk : Status::kWarmup;
    }
    for (int e = 0; e < config_.stagger; ++e) {
      if (phase_[e] < 0) {
        ++phase_[e];
        continue;
      }
      windows_[e].update(a, f);
      if (++phase_[e] == window_samples_) {
        harvest(windows_[e].mass(), windows_[e].damping(), windows_[e].stiffness());
        windows_[e].reseed();
        phase_[e] = 0;
      }
    }
    work();
    return ready() ? Status::kOk : Status::kWarmup;
  }

  /// Same as update(const Scalar*, const Scalar*) for Eigen vectors.
  /// @realtime no allocation, no throw
  template <class A, class F>
  Status update(const Eigen::MatrixBase<A>& accel, const Eigen::MatrixBase<F>& force) noexcept {
    return update(accel.derived().data(), force.derived().data());
  }

  /// Running estimates of all parameters: m_1..m_N [kg], c_1..c_N [N s/m], k_1..k_{N+1} [N/m]
  /// (NaN before the first window result; k_{N+1} = 0 with a free end; for N = 1 with walls
  /// k_1 holds k_1 + k_2 and k_2 is NaN).
  const Vector<Scalar, kParams>& estimate() const noexcept { return estimate_; }
  /// One-standard-deviation statistical uncertainty of estimate() [same units].
  const Vector<Scalar, kParams>& sigma() const noexcept { return sigma_; }
  /// Running masses m_i [kg].
  Eigen::Map<const Vector<Scalar, N>> mass() const noexcept {
    return Eigen::Map<const Vector<Scalar, N>>(estimate_.data(), n_);
  }
  /// Running dampings c_i [N s/m].
  Eigen::Map<const Vector<Scalar, N>> damping() const noexcept {
    return Eigen::Map<const Vector<Scalar, N>>(estimate_.data() + n_, n_);
  }
  /// Running springs k_1..k_{N+1} [N/m].
  Eigen::Map<const Vector<Scalar, N == Dynamic ? Dynamic : N + 1>> stiffness() const noexcept {
    return Eigen::Map<const Vector<Scalar, N == Dynamic ? Dynamic : N + 1>>(estimate_.data() + 2 * n_, n_ + 1);
  }
  /// True once every identified parameter has a running estimate.
  bool ready() const noexcept {
    for (int j = 0; j < params_; ++j)
      if (known_[j] == Known::kEstimated && !std::isfinite(estimate_(j))) return false;
    return true;
  }

  /// Change events raised by the last update() (0 .. params()).
  int events() const noexcept { return event_count_; }
  /// Event i (0 .. events()-1) of the last update().
  const Event& event(int i) const noexcept { return events_[static_cast<std::size_t>(i)]; }
  /// Change events since construction or reset().
  long total_events() const noexcept { return total_events_; }

  /// The latest window result (fused as in ChainEstimator; NaN where that window was not valid).
  const Vector<Scalar, kParams>& last_window() const noexcept { return last_window_; }
  /// Its variance per parameter (weak form; NaN for algebraic windows) [parameter units^2].
  const Vector<Scalar, kParams>& last_variance() const noexcept { return last_variance_; }
  /// The weak-form windows of the tracks, the change detector and the short joint sum (nullptr
  /// with algebraic windows), e.g. for noise_rms().
  const WeakForm* weak_form() const noexcept { return weak_.get(); }
  /// The long weak-form windows (`long_window_s`; nullptr without them).
  const WeakForm* long_windows() const noexcept { return long_.get(); }
  /// Weak form: true if parameter j is reported from the long windows' joint sum.
  bool from_long_windows(int j) const noexcept { return long_joint_ && best_joint(j) == long_joint_.get(); }
  /// Samples discarded as dropouts (stuck or clipped accelerations) since construction or reset().
  long dropout_samples() const noexcept { return dropout_samples_; }
  /// Runs of dropout samples since construction or reset().
  long dropout_runs() const noexcept { return dropout_runs_; }
  /// Kind of the latest dropout run (kNone: none yet) and its acceleration channel (0-based, -1: none).
  Dropout last_dropout() const noexcept { return last_dropout_; }
  int dropout_channel() const noexcept { return dropout_channel_; }
  /// Weak form: windows kept out of the joint sums by `misfit_ratio` since construction or reset().
  long screened_windows() const noexcept { return screened_; }
  /// Weak form: misfit of the latest window (WeakFormWindows::misfit(); NaN before a weighted one).
  double last_misfit() const noexcept { return weak_ ? weak_->misfit() : std::numeric_limits<double>::quiet_NaN(); }
  /// Window results harvested since construction or reset().
  long window_results() const noexcept { return results_; }
  /// Window results aggregated into parameter j's estimate since its last restart.
  long since_restart(int j) const noexcept { return tracks_[static_cast<std::size_t>(j)].since; }
  /// Per-window spread (1.4826 MAD of the ring) of parameter j [parameter units].
  Scalar window_spread(int j) const noexcept { return tracks_[static_cast<std::size_t>(j)].spread; }
  /// Samples consumed since construction or reset().
  long samples() const noexcept { return samples_; }
  /// Window length M [samples].
  long window_samples() const noexcept { return window_samples_; }
  /// Samples between two window results.
  long hop_samples() const noexcept { return weak_form_ ? weak_->hop_samples() : window_samples_ / config_.stagger; }
  /// Samples skipped after a (re)start while the prefilter settles (0 without prefilter).
  long settle_samples() const noexcept { return settle_; }
  /// Prefilter cut-off in force [Hz] (0: off).
  Scalar prefilter_hz() const noexcept {
    return filtered_ ? (config_.prefilter_hz < Scalar(0) ? Scalar(0.05) / config_.dt : config_.prefilter_hz)
                     : Scalar(0);
  }
  /// Window results in the step test (config.confirm, or 2K+1).
  int confirm() const noexcept { return confirm_; }
  /// Parameters aggregated per sample (params() when not amortized).
  int budget() const noexcept { return budget_; }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }
  /// Number of DOF.
  int dofs() const noexcept { return n_; }
  /// Number of reported parameters, 3 dofs() + 1.
  int params() const noexcept { return params_; }

 private:
  enum class Known { kEstimated, kZero, kUnidentifiable };

  static constexpr int kMisfits = 16;
  struct MisfitRing {
    std::array<double, kMisfits> value{};
    int head = 0, count = 0;
  };

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
    Scalar cusum_hi = Scalar(0), cusum_lo = Scalar(0);
    std::array<Scalar, Capacity> block_sd{};  // the current block's window sigmas (0: unknown)
    Scalar spread = std::numeric_limits<Scalar>::quiet_NaN();  // per-window sigma
    Scalar relative_spread = std::numeric_limits<Scalar>::quiet_NaN();  // carried over a restart
    bool spread_ok = false;  // spread measured on >= min_windows results: the tests may run
  };

  static typename Window::Config window_config(const Config& c) noexcept {
    typename Window::Config w;
    w.dt = c.dt;
    w.boundary = c.boundary;
    w.validity = c.validity;
    return w;
  }

  static Scalar resolved_window(const Config& c) noexcept {
    if (c.window_s != Scalar(-1)) return c.window_s;
    return c.method == WindowMethod::kWeakForm ? Scalar(0.5) : Scalar(0.3);
  }

  static Scalar resolved_long_window(const Config& c) noexcept {
    return c.long_window_s == Scalar(-1) ? Scalar(3) * resolved_window(c) : c.long_window_s;
  }

  // The long windows: as the tracks' windows, resolved_long_window(c) long, with as many test
  // functions (F = 2 band W + 1): the same cost per window and per sample, a finer resolution in
  // frequency over a lower band (where the band matters, the short sum's variance is the smaller).
  static typename WeakForm::Config long_config(const Config& c) noexcept {
    typename WeakForm::Config w = weak_config(c);
    w.window_s = resolved_long_window(c);
    w.band_hz = static_cast<Scalar>(WeakForm::band_of(w)) * resolved_window(c) / w.window_s;
    return w;
  }

  static typename WeakForm::Config weak_config(const Config& c) noexcept {
    typename WeakForm::Config w;
    w.dt = c.dt;
    w.boundary = c.boundary;
    w.window_s = resolved_window(c);
    w.stagger = c.stagger;
    w.band_hz = c.band_hz;
    w.accel_noise = c.accel_noise;
    w.force_noise = c.force_noise;
    w.bias_compensation = c.bias_compensation;
    w.weighted = c.gls;
    return w;
  }

  static const Config& checked(const Config& c, int n) {
    const ContinuousConfigError e = validate(c, n);
    if (e != ContinuousConfigError::kNone) detail::config_error(to_string(e));
    return c;
  }

  template <std::size_t... I>
  static std::array<Window, sizeof...(I)> make_windows(const typename Window::Config& c, int n,
                                                       std::index_sequence<I...>) {
    return {{((void)I, Window(c, n))...}};
  }

  // Every value finite (squared too) and, once a window of samples has set each channel's running mean
  // square, within outlier_ratio times its RMS; the running mean squares learn from the
  // plausible samples only. A whole window of finite samples out of range in a row is a new
  // level, not an outlier (a quiet channel that starts to move): the scales are learnt anew.
  bool plausible(const Scalar* accel, const Scalar* force) noexcept {
    const Scalar limit = config_.outlier_ratio * config_.outlier_ratio;
    const bool armed = limit > Scalar(0) && accepted_ >= window_samples_;
    bool finite = true, in_range = true;
    for (int i = 0; i < n_; ++i) {
      // finite, and finite squared: beyond sqrt(max) nothing is a measurement (and the
      // prefilter and the mean squares would overflow)
      finite &= std::isfinite(accel[i] * accel[i]) && std::isfinite(force[i] * force[i]);
      if (armed)
        in_range &= !(accel[i] * accel[i] > limit * mean_square_[i]) &&
                    !(force[i] * force[i] > limit * mean_square_[n_ + i]);
    }
    if (!finite) return false;
    if (!in_range) {
      if (++out_of_range_ < window_samples_) return false;
      mean_square_.fill(Scalar(0));
      accepted_ = 0;
    }
    out_of_range_ = 0;
    const Scalar alpha = Scalar(1) / static_cast<Scalar>(window_samples_);
    for (int i = 0; i < n_; ++i) {
      mean_square_[i] += alpha * (accel[i] * accel[i] - mean_square_[i]);
      mean_square_[n_ + i] += alpha * (force[i] * force[i] - mean_square_[n_ + i]);
    }
    ++accepted_;
    return true;
  }

  // The misfit screen (`misfit_ratio`): false if the window fits far worse than the windows
  // before it, short and long alike (a misfit is per degree of freedom: about 1 for both); every
  // finite misfit joins the ring of the newest kMisfits. One ring: the long windows' first
  // weighted ones are compared with the short windows before them, not with each other.
  bool fits(double misfit) noexcept {
    if (!std::isfinite(misfit)) return true;  // unweighted or failed: joint_add() decides
    MisfitRing& ring = misfits_;
    double reference = 1.0;
    if (ring.count > 0) {
      std::copy(ring.value.begin(), ring.value.begin() + ring.count, misfit_scratch_.begin());
      reference = std::max(reference, detail::median_inplace(misfit_scratch_.data(), ring.count));
    }
    ring.value[static_cast<std::size_t>(ring.head)] = misfit;
    ring.head = (ring.head + 1) % kMisfits;
    ring.count = std::min(ring.count + 1, kMisfits);
    const double ratio = static_cast<double>(config_.misfit_ratio);
    const bool ok = !(ratio > 0.0 && misfit > ratio * reference);
    if (!ok) ++screened_;
    return ok;
  }

  // A stuck or clipped acceleration (detail/dropout.hpp); counts a new run when the previous
  // sample was not one.
  bool dropped(const Scalar* accel) noexcept {
    int channel = -1;
    const Dropout kind = dropout_.check(accel, channel);
    const bool was = in_dropout_;
    in_dropout_ = kind != Dropout::kNone;
    if (!in_dropout_) return false;
    ++dropout_samples_;
    if (!was) {
      ++dropout_runs_;
      last_dropout_ = kind;
      dropout_channel_ = channel;
    }
    return true;
  }

  void restart_windows() noexcept {
    if (weak_) weak_->restart();
    if (long_) long_->restart();
    filter_.reset();
    for (int e = 0; e < MaxStagger; ++e) {
      windows_[e].reseed();
      phase_[e] = e < config_.stagger ? -(offset_[e] + settle_) : 0;
    }
  }

  template <class M, class C, class K>
  void harvest(const M& mass, const C& damping, const K& stiffness) noexcept {
    finish_pending();
    for (int i = 0; i < n_; ++i) {
      last_window_(i) = mass(i);
      last_window_(n_ + i) = damping(i);
    }
    for (int j = 0; j <= n_; ++j) last_window_(2 * n_ + j) = stiffness(j);
    last_variance_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
    pending_ = last_window_;
    pending_var_ = last_variance_;
    pending_next_ = 0;
    ++results_;
  }

  void harvest(const Vector<Scalar, kParams>& result, const Vector<Scalar, kParams>& variance) noexcept {
    finish_pending();
    last_window_ = result;
    last_variance_ = variance;
    pending_ = result;
    pending_var_ = variance;
    pending_next_ = 0;
    ++results_;
  }

  // Finish the previous result first (only if the budget was too small, e.g. a bad sample
  // shifted the schedule), so no result is lost.
  void finish_pending() noexcept {
    while (pending_next_ < params_) process(pending_next_++);
  }

  void work() noexcept {
    for (int b = 0; b < budget_ && pending_next_ < params_; ++b) process(pending_next_++);
  }

  // Copy the newest `count` entries of a ring into scratch_, newest last.
  int newest(const std::array<Scalar, Capacity>& ring, int head, int count) noexcept {
    for (int i = 0; i < count; ++i)
      scratch_[static_cast<std::size_t>(count - 1 - i)] =
          ring[static_cast<std::size_t>((head - 1 - i + Capacity) % Capacity)];
    return count;
  }

  Scalar floor_spread(const Track& t, Scalar estimate) const noexcept {
    return std::max(t.spread, config_.min_relative_spread * std::abs(estimate));
  }

  void process(int j) noexcept {
    if (known_[j] != Known::kEstimated) return;
    const Scalar x = pending_(j);
    if (!std::isfinite(x)) return;
    Track& t = tracks_[j];
    const Scalar est = track_(j);
    // The window's own sigma (weak form with GLS weights), where it exceeds the track's
    // spread: a window in a lull of the excitation is uncertain, and says so.
    const Scalar v = pending_var_(j);
    const Scalar sd = std::isfinite(v) && v > Scalar(0) ? std::sqrt(v) : Scalar(0);
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

    // Step test: the median z of the last `confirm` results.
    if (config_.detect && t.since >= config_.min_windows && t.z_count >= confirm_) {
      newest(t.z, t.head, confirm_);
      const Scalar mz = detail::median_inplace(scratch_.data(), confirm_);
      if (std::abs(mz) > config_.step_threshold) {
        restart_step(j, t, mz);
        return;
      }
    }

    // Blocks: median of the last `block` results into the running mean; drift test on it,
    // on the scale of the larger of the track's spread and the block's median window sigma.
    t.block_sd[static_cast<std::size_t>(t.in_block)] = sd;
    if (++t.in_block == config_.block) {
      t.in_block = 0;
      newest(t.value, t.head, config_.block);
      const Scalar bm = detail::median_inplace(scratch_.data(), config_.block);
      if (config_.detect && t.s0 > Scalar(0) && t.spread_ok) {
        std::copy(t.block_sd.begin(), t.block_sd.begin() + config_.block, scratch_.begin());
        const Scalar block_sd = detail::median_inplace(scratch_.data(), config_.block);
        const Scalar sb = block_scale_ * std::max(floor_spread(t, est), block_sd);
        if (sb > Scalar(0)) {
          const Scalar d = std::clamp((bm - est) / sb, -config_.cusum_clip, config_.cusum_clip);
          t.cusum_hi = std::max(Scalar(0), t.cusum_hi + d - config_.cusum_reference);
          t.cusum_lo = std::max(Scalar(0), t.cusum_lo - d - config_.cusum_reference);
          if (t.cusum_hi > config_.cusum_threshold || t.cusum_lo > config_.cusum_threshold) {
            restart_drift(j, t, bm);
            return;
          }
        }
      }
      t.s0 = forget_ * t.s0 + Scalar(1);
      t.s1 = forget_ * t.s1 + bm;
      t.s2 = forget_ * t.s2 + bm * bm;
      t.s0sq = forget_ * forget_ * t.s0sq + Scalar(1);
    }
    refresh(j, t);
  }

  // Spread, estimate and uncertainty of parameter j from its track.
  void refresh(int j, Track& t) noexcept {
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
            std::sqrt(std::max(Scalar(1), static_cast<Scalar>(t.count) * config_.overlap_efficiency));
    }
    track_(j) = est;
    track_sigma_(j) = sig;
    publish(j);
  }

  // The reported estimate of parameter j: the joint solution where it exists, else the track's.
  void publish(int j) noexcept {
    if (const Joint* J = best_joint(j)) {
      estimate_(j) = static_cast<Scalar>(J->solution(j));
      sigma_(j) = static_cast<Scalar>(std::sqrt(J->inverse(j, j) / static_cast<double>(config_.joint_efficiency)));
    } else {
      estimate_(j) = track_(j);
      sigma_(j) = track_sigma_(j);
    }
  }

  void clear_aggregation(Track& t) noexcept {
    t.since = t.count;
    t.fresh = 0;
    t.z_count = 0;
    t.in_block = 0;
    t.s0 = t.s1 = t.s2 = t.s0sq = Scalar(0);
    t.cusum_hi = t.cusum_lo = Scalar(0);
  }

  void restart_step(int j, Track& t, Scalar mz) noexcept {
    // Keep the results of the run that agree with the new level (same sign, beyond half the
    // threshold); the others are from before the change or straddle it.
    const int n = confirm_;
    int kept = 0;
    for (int i = n - 1; i >= 0; --i) {  // oldest first into scratch_
      const std::size_t slot = static_cast<std::size_t>((t.head - 1 - i + Capacity) % Capacity);
      const Scalar zi = t.z[slot];
      if ((zi > Scalar(0)) == (mz > Scalar(0)) && std::abs(zi) > Scalar(0.5) * config_.step_threshold)
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
    clear_aggregation(t);
    finish_restart(j, t, ChangeKind::kStep);
  }

  void restart_drift(int j, Track& t, Scalar) noexcept {
    t.count = std::min(t.count, config_.block);  // the block just completed
    clear_aggregation(t);
    finish_restart(j, t, ChangeKind::kDrift);
  }

  // Both joint sums forget j (joint_restart), then the event is recorded.
  void finish_restart(int j, Track& t, ChangeKind kind) noexcept {
    for (Joint* J : {joint_.get(), long_joint_.get()})
      if (J) joint_restart(*J, j);
    const Scalar before = estimate_(j);
    refresh(j, t);
    Event& ev = events_[event_count_ < params_ ? event_count_ : params_ - 1];
    ev.sample = samples_ - 1;
    ev.param = j;
    ev.kind = kind;
    ev.before = before;
    ev.after = estimate_(j);
    if (event_count_ < params_) ++event_count_;
    ++total_events_;
  }

  // Sum of the GLS-weighted weak-form windows' normal equations of one window length since
  // the start (with `horizon_s` forgetting), and a ring of the newest windows' systems so that
  // a restart of one parameter can take them out again. Heap-allocated at construction (weak
  // form only).
  struct Joint {
    Eigen::MatrixXd normal, inverse;
    Eigen::VectorXd rhs, solution, column;
    Eigen::LDLT<Eigen::MatrixXd> ldlt;
    detail::Storage<Eigen::MatrixXd, Dynamic> ring_normal;
    detail::Storage<Eigen::VectorXd, Dynamic> ring_rhs;
    detail::Storage<int, Dynamic> fresh;  // per parameter: windows since its restart
    detail::Storage<bool, Dynamic> trusted;  // per parameter: the joint estimate is reported
    int head = 0, count = 0, size = 0;
    int stage = 0;  // solve pending: 1 factor next sample, 2 solve next sample, 0 none
    double forget = 1.0;
    bool valid = false;

    Joint(int params, int ring) : ldlt(params), size(ring) {
      normal.setZero(params, params);
      inverse.setZero(params, params);
      rhs.setZero(params);
      solution.setZero(params);
      column.setZero(params);
      ring_normal.resize(ring);
      ring_rhs.resize(ring);
      fresh.resize(params);
      trusted.resize(params);
      for (int r = 0; r < ring; ++r) {
        ring_normal[r].setZero(params, params);
        ring_rhs[r].setZero(params);
      }
    }
    void clear() noexcept {
      normal.setZero();
      rhs.setZero();
      fresh.fill(0);
      trusted.fill(true);
      head = count = stage = 0;
      valid = false;
    }
    int slot(int age) const noexcept {  // age 0: the newest window
      return ((head - 1 - age) % size + size) % size;
    }
  };

  // The joint sum that reports parameter j: of the valid ones that trust it, the one with the
  // smaller variance (both sums overlap their windows alike, K per window length); none: the track.
  const Joint* best_joint(int j) const noexcept {
    const Joint* best = nullptr;
    for (const Joint* J : {joint_.get(), long_joint_.get()})
      if (J && J->valid && J->trusted[j] && (!best || J->inverse(j, j) < best->inverse(j, j))) best = J;
    return best;
  }

  // The joint sum of windows like w's: its ring spans `block` hops of the tracks' windows (and
  // more than K windows of its own); forgetting per hop of its own with `horizon_s`.
  std::unique_ptr<Joint> make_joint(const WeakForm& w) const {
    const long hop = w.hop_samples();
    const long ring = (config_.block * weak_->hop_samples() + hop - 1) / hop;
    auto J = std::make_unique<Joint>(params_, static_cast<int>(std::max<long>(ring, 2 * config_.stagger + 1)));
    if (config_.horizon_s > Scalar(0))
      J->forget = std::exp(-static_cast<double>(hop) * static_cast<double>(config_.dt / config_.horizon_s));
    return J;
  }

  // A weighted window of w with a finite result joins the joint sum J, which is solved again.
  void joint_add(Joint& J, const WeakForm& w) noexcept {
    const auto& x = w.result();
    for (int j = 0; j < params_; ++j)
      if (known_[j] == Known::kEstimated && !std::isfinite(x(j))) return;
    if (!w.result_weighted()) return;
    if (J.forget < 1.0) {
      J.normal *= J.forget;
      J.rhs *= J.forget;
      for (int r = 0; r < J.size; ++r) {
        J.ring_normal[r] *= J.forget;
        J.ring_rhs[r] *= J.forget;
      }
    }
    const int r = J.head;
    J.ring_normal[r] = w.normal();
    J.ring_rhs[r] = w.rhs();
    J.head = (J.head + 1) % J.size;
    J.count = std::min(J.count + 1, J.size);
    J.normal += w.normal();
    J.rhs += w.rhs();
    for (int j = 0; j < params_; ++j) {
      if (J.trusted[j] || ++J.fresh[j] < J.size) continue;
      joint_forget(J, j, J.size - config_.stagger);
      J.trusted[j] = true;
    }
    if (config_.amortize) {
      J.stage = 1;  // factored on the next sample, solved on the one after
    } else {
      joint_solve(J);
    }
  }

  // One O(P^3) part of J's pending solve per sample: the factorisation, then the solution, the
  // inverse and the reported estimates.
  void joint_step(Joint& J) noexcept {
    if (J.stage == 1) {
      J.ldlt.compute(J.normal);
      J.stage = 2;
    } else {
      joint_publish(J);
      J.stage = 0;
    }
  }

  void joint_solve(Joint& J) noexcept {
    J.ldlt.compute(J.normal);
    joint_publish(J);
    J.stage = 0;
  }

  void joint_publish(Joint& J) noexcept {
    J.valid = J.ldlt.info() == Eigen::Success && J.ldlt.vectorD().minCoeff() > 0.0;
    if (J.valid) {
      J.solution = J.rhs;
      J.ldlt.solveInPlace(J.solution);
      J.inverse.setIdentity();
      J.ldlt.solveInPlace(J.inverse);
      J.valid = J.solution.allFinite();
    }
    for (int j = 0; j < params_; ++j)
      if (known_[j] == Known::kEstimated) publish(j);
  }

  // Take the `recent` newest windows out, marginalise parameter j out of the rest (its old
  // information is void, the others' is kept: the Schur complement), pin j by a negligible
  // prior at the track's estimate (so the system stays definite), put the recent windows back.
  void joint_forget(Joint& J, int j, int recent) noexcept {
    recent = std::min(recent, J.count);
    for (int age = 0; age < recent; ++age) {
      const int r = J.slot(age);
      J.normal -= J.ring_normal[r];
      J.rhs -= J.ring_rhs[r];
    }
    const double d = J.normal(j, j);
    if (d > 0.0) {
      J.column = J.normal.col(j);
      const double bj = J.rhs(j);
      for (int b = 0; b < params_; ++b) {
        for (int a = 0; a < params_; ++a) J.normal(a, b) -= J.column(a) * J.column(b) / d;
        J.rhs(b) -= J.column(b) * bj / d;
      }
    }
    J.normal.row(j).setZero();
    J.normal.col(j).setZero();
    const double prior = 1e-12 * (d > 0.0 ? d : 1.0);
    J.normal(j, j) = prior;
    J.rhs(j) = prior * static_cast<double>(track_(j));
    for (int age = 0; age < recent; ++age) {
      const int r = J.slot(age);
      J.normal += J.ring_normal[r];
      J.rhs += J.ring_rhs[r];
    }
  }

  // Parameter j restarted (step or drift): the windows of J's ring (the newest, which may
  // straddle the change and fit no single value of j) leave J for every parameter; J forgets
  // all it knew of j, and j is not reported from J until a ring of windows has arrived since;
  // then j is forgotten once more, except for the newest ring minus K windows (none of which
  // straddles the change), and J may report j again.
  void joint_restart(Joint& J, int j) noexcept {
    for (int age = 0; age < J.count; ++age) {
      const int r = J.slot(age);
      J.normal -= J.ring_normal[r];
      J.rhs -= J.ring_rhs[r];
      J.ring_normal[r].setZero();
      J.ring_rhs[r].setZero();
    }
    joint_forget(J, j, 0);
    J.fresh[j] = 0;
    J.trusted[j] = false;
    joint_solve(J);
  }

  static constexpr int kChannels = N == Dynamic ? Dynamic : 2 * N;

  Config config_;
  int n_;
  int params_;
  std::array<Window, MaxStagger> windows_;
  detail::ButterworthLowpass<Scalar, kChannels> filter_{};
  detail::Storage<Scalar, kChannels> io_{};
  detail::Storage<Scalar, kChannels> mean_square_{};  // running mean square of every raw channel
  long accepted_ = 0;  // plausible samples since construction, reset() or a new level
  MisfitRing misfits_{};  // newest window misfits
  std::array<double, kMisfits> misfit_scratch_{};
  long screened_ = 0;
  long out_of_range_ = 0;  // finite samples out of range in a row
  detail::DropoutDetector<Scalar, N> dropout_{};
  bool in_dropout_ = false;
  long dropout_samples_ = 0;
  long dropout_runs_ = 0;
  Dropout last_dropout_ = Dropout::kNone;
  int dropout_channel_ = -1;
  bool filtered_ = false;
  long settle_ = 0;
  std::array<long, MaxStagger> phase_{};
  std::array<long, MaxStagger> offset_{};
  long window_samples_ = 0;
  int budget_ = 0;
  int confirm_ = 1;
  Scalar forget_ = Scalar(1);
  Scalar block_scale_ = Scalar(1);
  detail::Storage<Known, kParams> known_{};
  detail::Storage<Track, kParams> tracks_{};
  std::array<Scalar, Capacity> scratch_{};
  Vector<Scalar, kParams> estimate_, sigma_, last_window_, last_variance_, pending_, pending_var_;
  std::unique_ptr<WeakForm> weak_;
  std::unique_ptr<WeakForm> long_;  // the long windows (`long_window_s`)
  std::unique_ptr<Joint> joint_, long_joint_;  // the joint sums of weak_'s and of long_'s windows
  Vector<Scalar, kParams> track_, track_sigma_;
  bool weak_form_ = false;

  int pending_next_ = 0;
  detail::Storage<Event, kParams> events_{};
  int event_count_ = 0;
  long total_events_ = 0;
  long samples_ = 0;
  long results_ = 0;
};

}  // namespace algid
