#pragma once
/// @file continuous_estimator.hpp
/// Continuous operation of the algebraic estimator: automatic reseeding, a running estimate
/// with an uncertainty per parameter, and a change detector.
///
/// Why: one growing window from t0 degrades under measurement noise (the iterated integrals
/// of the noise grow faster than the information), so the estimator is restarted on short
/// windows and the window results are aggregated.
///
/// A sample goes through four concepts, each in a header of its own:
///   1. the InputScreen (input_screen.hpp): non-finite samples, outliers, dropouts are refused;
///   2. the window source, a type chosen at compile time: WeakFormSource (weak_form_source.hpp,
///      the default: GLS over all weak-form rows of a 0.5 s window, and 1.5 s ones) or
///      AlgebraicWindows (algebraic_windows.hpp: the paper's staggered ChainEstimators behind a
///      prefilter);
///   3. aggregation: the RobustTracks of the window results per parameter (robust_tracks.hpp),
///      and with weak-form windows the JointSums of their normal equations (joint_sum.hpp), from
///      which each parameter is reported where they trust it;
///   4. the ChangeDetector (change_detector.hpp): step and drift tests on the tracks; a restart
///      of a parameter restarts its track and makes the joint sums forget it.
///
/// Real-time contract: construction validates the configuration and may throw
/// (std::invalid_argument; call `validate()` first where exceptions are off). `update()`,
/// `reset()`, `record()` and every accessor are noexcept and allocate nothing. The
/// per-parameter work of a window result (two nth_element passes over at most Capacity values)
/// is spread over the samples until the next result (`amortize`), so no single sample pays for
/// all 3n+1 parameters; the estimates therefore lag the window end by at most one hop. The
/// joint sums' O((3n+1)^3) parts each take a sample of their own.
///
/// Storage: the window source's (see its header), the tracks' 3 (3n+1) Capacity scalars
/// (about 75 KiB for n = 3), inside the object for a fixed N with AlgebraicWindows; allocated by
/// the constructor for N = Dynamic and for the weak-form windows.

#include "algid/algebraic_windows.hpp"
#include "algid/change_detector.hpp"
#include "algid/continuous_error.hpp"
#include "algid/detail/storage.hpp"
#include "algid/histories.hpp"
#include "algid/input_screen.hpp"
#include "algid/robust_tracks.hpp"
#include "algid/types.hpp"
#include "algid/weak_form_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace algid {

/// Configuration of a ContinuousEstimator: its window source's and one per concept. The
/// defaults are the ones benchmarked in bench/continuous.py (1 kHz, broadband forcing, 20-60 dB SNR).
template <class WindowsConfig, class Scalar>
struct ContinuousConfig : WindowsConfig, ScreenConfig<Scalar>, TrackConfig<Scalar>, DetectorConfig<Scalar> {
  bool amortize = true;  ///< spread the per-parameter work and the joint solves over the samples
};

/// Continuous estimator of an N-DOF chain (see the file comment).
/// @tparam Windows the window source: WeakFormSource<N, Scalar> or AlgebraicWindows<N, Scalar>.
/// @tparam Capacity window results kept per parameter (ring); bounds `block`, `confirm`.
template <class Windows, int Capacity = 64>
class ContinuousEstimator {
  using Scalar = typename Windows::ScalarType;
  static constexpr int N = Windows::kDofs;
  static_assert(N >= 1 || N == Dynamic, "a chain has at least one DOF");

 public:
  /// Scalar type of samples and estimates.
  using ScalarType = Scalar;
  /// Configuration type.
  using Config = ContinuousConfig<typename Windows::Config, Scalar>;
  /// Change event type.
  using Event = ChangeEvent<Scalar>;
  /// Number of DOF (Dynamic: see dofs()).
  static constexpr int kDofs = N;
  /// Number of reported parameters: m_1..m_N, c_1..c_N, k_1..k_{N+1} (Dynamic: see params()).
  static constexpr int kParams = N == Dynamic ? Dynamic : 3 * N + 1;
  /// Ring capacity per parameter [window results].
  static constexpr int kCapacity = Capacity;
  /// Most windows in flight.
  static constexpr int kMaxStagger = Windows::kMaxStagger;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ContinuousConfigError validate(const Config& c, int n = N) noexcept {
    ContinuousConfigError e = Windows::validate(c, n);
    if (e == ContinuousConfigError::kNone) e = static_cast<const TrackConfig<Scalar>&>(c).validate(Capacity);
    if (e == ContinuousConfigError::kNone) e = static_cast<const DetectorConfig<Scalar>&>(c).validate(Capacity);
    if (e == ContinuousConfigError::kNone && !c.valid_outlier_ratio()) e = ContinuousConfigError::kBadOutlierRatio;
    if (e == ContinuousConfigError::kNone && !c.valid_dropout()) e = ContinuousConfigError::kBadDropout;
    return e;
  }

  /// Configure; throws std::invalid_argument on a bad configuration.
  explicit ContinuousEstimator(const Config& config, int n = N)
      : config_(checked(config, n)),
        n_(detail::fixed_or<N>(n)),
        params_(3 * n_ + 1),
        windows_(config, n_),
        joints_(windows_.joints(params_, config.block, config.horizon_s, config.amortize)) {
    screen_.configure(n_, windows_.window_samples(), config);
    tracks_.configure(params_, config, windows_.window_samples(), config.stagger, config.dt, config.overlap_efficiency);
    detector_.configure(params_, config, config.stagger, Capacity);
    known_.resize(params_);
    events_.resize(params_);
    for (auto* v : {&estimate_, &sigma_, &last_window_, &last_variance_, &pending_, &pending_var_}) v->setZero(params_);
    const long spacing = windows_.min_spacing();  // fewest samples between two window results
    budget_ = config_.amortize ? static_cast<int>((params_ + spacing - 1) / spacing) : params_;
    for (int j = 0; j < params_; ++j) known_[j] = Known::kEstimated;
    if (config_.boundary == Boundary::kFree) known_[params_ - 1] = Known::kZero;
    if (n_ == 1 && config_.boundary == Boundary::kFixed) known_[params_ - 1] = Known::kUnidentifiable;
    reset();
  }

  /// Forget everything (windows, aggregation, events); the next sample starts the schedule.
  /// @realtime no allocation, no throw
  void reset() noexcept {
    windows_.reset();
    joints_.reset();
    screen_.reset();
    detector_.reset();
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    for (int j = 0; j < params_; ++j) {
      estimate_(j) = known_[j] == Known::kZero ? Scalar(0) : nan;
      sigma_(j) = known_[j] == Known::kZero ? Scalar(0) : nan;
      last_window_(j) = estimate_(j);
    }
    tracks_.reset(estimate_, sigma_);
    last_variance_.setConstant(nan);
    pending_.setConstant(nan);
    pending_var_.setConstant(nan);
    pending_next_ = params_;
    samples_ = results_ = total_events_ = 0;
    event_count_ = 0;
  }

  /// Consume one simultaneous sample of the accelerations [m/s^2] and forces [N]. A sample the
  /// screen refuses is discarded and the windows in flight are dropped (the aggregation is
  /// kept): kBadInput or kDropout. Returns kWarmup until every identified parameter has an estimate.
  /// @realtime no allocation, no throw, O(K N) plus at most `budget` parameters' aggregation
  Status update(const Scalar* accel, const Scalar* force) noexcept {
    event_count_ = 0;
    ++samples_;
    const Status screened = screen_.check(accel, force);  // 1. screen
    if (screened != Status::kOk) {
      windows_.restart();
      aggregate();
      return screened;
    }
    if (joints_.step()) publish_all();  // a pending joint solve advances
    Sink sink{*this};
    windows_.update(accel, force, sink);  // 2. windows: results into harvest() and the joint sums
    aggregate();                          // 3.-4. the tracks' share of this sample, with the tests
    return ready() ? Status::kOk : Status::kWarmup;
  }

  /// Same as update(const Scalar*, const Scalar*) for Eigen vectors.
  /// @realtime no allocation, no throw
  template <class A, class F>
  Status update(const Eigen::MatrixBase<A>& accel, const Eigen::MatrixBase<F>& force) noexcept {
    return update(accel.derived().data(), force.derived().data());
  }

  /// Consume a record of T samples (T x n, row-major) and write the status of every sample and
  /// the estimates of every `out.stride`-th into `out` (see ContinuousHistories); each window
  /// result goes to `observe.window(sample)` (read last_window(), last_variance(),
  /// last_misfit()), each change event to `observe.event(event)`.
  /// @realtime no allocation; no throw unless `observe` throws
  template <class Observer>
  void record(const Scalar* accel, const Scalar* force, long T, const ContinuousHistories<Scalar>& out,
              Observer&& observe) {
    const long first = samples_;
    for (long t = 0, row = 0; t < T; ++t) {
      const long results = results_;
      out.status[t] = static_cast<std::int8_t>(update(accel + t * n_, force + t * n_));
      for (int i = 0; i < event_count_; ++i) observe.event(events_[static_cast<std::size_t>(i)]);
      if (results_ != results) observe.window(first + t);
      if (t % out.stride != 0) continue;
      std::copy(estimate_.data(), estimate_.data() + params_, out.estimate + row * params_);
      std::copy(sigma_.data(), sigma_.data() + params_, out.sigma + row * params_);
      out.sample[row++] = first + t;
    }
  }

  /// record() without the window results and events. @realtime no allocation, no throw
  void record(const Scalar* accel, const Scalar* force, long T, const ContinuousHistories<Scalar>& out) noexcept {
    struct Ignore {
      void window(long) noexcept {}
      void event(const Event&) noexcept {}
    };
    record(accel, force, T, out, Ignore{});
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
  /// The window source.
  const Windows& windows() const noexcept { return windows_; }
  /// Weak form: true if parameter j is reported from the long windows' joint sum.
  bool from_long_windows(int j) const noexcept { return joints_.from_long(j); }
  /// The input screen (dropout counters).
  const InputScreen<N, Scalar>& screen() const noexcept { return screen_; }
  /// Samples discarded as dropouts (stuck or clipped accelerations) since construction or reset().
  long dropout_samples() const noexcept { return screen_.dropout_samples(); }
  /// Runs of dropout samples since construction or reset().
  long dropout_runs() const noexcept { return screen_.dropout_runs(); }
  /// Kind of the latest dropout run (kNone: none yet) and its acceleration channel (0-based, -1: none).
  Dropout last_dropout() const noexcept { return screen_.last_dropout(); }
  int dropout_channel() const noexcept { return screen_.dropout_channel(); }
  /// Weak form: windows kept out of the joint sums by `misfit_ratio` since construction or reset().
  long screened_windows() const noexcept { return joints_.screened(); }
  /// Weak form: misfit of the latest window (WeakFormWindows::misfit(); NaN before a weighted one).
  double last_misfit() const noexcept { return windows_.misfit(); }
  /// Noise RMS of channel c (accelerations 0..n-1, forces n..2n-1) the windows estimated; -1: none.
  Scalar noise_rms(int c) const noexcept { return windows_.noise_rms(c); }
  /// Window results harvested since construction or reset().
  long window_results() const noexcept { return results_; }
  /// Window results aggregated into parameter j's estimate since its last restart.
  long since_restart(int j) const noexcept { return tracks_.since(j); }
  /// Per-window spread (1.4826 MAD of the ring) of parameter j [parameter units].
  Scalar window_spread(int j) const noexcept { return tracks_.spread(j); }
  /// Samples consumed since construction or reset().
  long samples() const noexcept { return samples_; }
  /// Window length M [samples].
  long window_samples() const noexcept { return windows_.window_samples(); }
  /// Samples between two window results.
  long hop_samples() const noexcept { return windows_.hop_samples(); }
  /// Samples skipped after a (re)start while the prefilter settles (0 without prefilter).
  long settle_samples() const noexcept { return windows_.settle_samples(); }
  /// Prefilter cut-off in force [Hz] (0: off).
  Scalar prefilter_hz() const noexcept { return windows_.prefilter_hz(); }
  /// Window results in the step test (config.confirm, or 2K+1).
  int confirm() const noexcept { return detector_.confirm(); }
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

  // What the window source hands its results to.
  struct Sink {
    ContinuousEstimator& e;
    const Scalar* model() const noexcept { return e.estimate_.data(); }
    void window(const Vector<Scalar, kParams>& result, const Vector<Scalar, kParams>& variance) noexcept {
      e.harvest(result, variance);
    }
    template <class W>
    void joint(int which, const W& w) noexcept {
      const auto estimated = [this](int j) { return e.known_[j] == Known::kEstimated; };
      if (e.joints_.add(which, w, estimated, e.tracks_.estimate())) e.publish_all();
    }
  };

  static const Config& checked(const Config& c, int n) {
    const ContinuousConfigError e = validate(c, n);
    if (e != ContinuousConfigError::kNone) detail::config_error(to_string(e));
    return c;
  }

  // A window result: the previous one is finished first (only if the budget was too small,
  // e.g. a bad sample shifted the schedule), so no result is lost.
  void harvest(const Vector<Scalar, kParams>& result, const Vector<Scalar, kParams>& variance) noexcept {
    while (pending_next_ < params_) process(pending_next_++);
    last_window_ = result;
    last_variance_ = variance;
    pending_ = result;
    pending_var_ = variance;
    pending_next_ = 0;
    ++results_;
  }

  // The budget's share of the pending result's parameters.
  void aggregate() noexcept {
    for (int b = 0; b < budget_ && pending_next_ < params_; ++b) process(pending_next_++);
  }

  // Parameter j of the pending result: into its track (aggregate), the step test, the block
  // median and the drift test (detect), the track's estimate, the reported one.
  void process(int j) noexcept {
    if (known_[j] != Known::kEstimated || !std::isfinite(pending_(j))) return;
    const Scalar est = tracks_.estimate()(j);
    const Scalar sd = tracks_.add(j, pending_(j), pending_var_(j));
    if (detector_.enabled() && tracks_.scored(j, detector_.confirm())) {
      const Scalar mz = tracks_.median_z(j, detector_.confirm());
      if (detector_.step(mz)) return restart(j, ChangeKind::kStep, mz);
    }
    Scalar median;
    if (tracks_.close_block(j, sd, median)) {
      const Scalar sb = detector_.enabled() ? tracks_.block_sigma(j) : Scalar(0);
      if (sb > Scalar(0) && detector_.drift(j, (median - est) / sb)) return restart(j, ChangeKind::kDrift, median);
      tracks_.accumulate(j, median);
    }
    tracks_.refresh(j);
    publish(j);
  }

  // A change of parameter j: its track restarts, the joint sums forget it, the event is recorded.
  void restart(int j, ChangeKind kind, Scalar mz) noexcept {
    if (kind == ChangeKind::kStep) {
      tracks_.restart_step(j, mz, detector_.confirm(), detector_.step_threshold());
    } else {
      tracks_.restart_drift(j);
    }
    detector_.clear(j);
    if (joints_.restart(j, static_cast<double>(tracks_.estimate()(j)))) publish_all();
    Event& ev = events_[event_count_ < params_ ? event_count_ : params_ - 1];
    ev.before = estimate_(j);
    tracks_.refresh(j);
    publish(j);
    ev.sample = samples_ - 1;
    ev.param = j;
    ev.kind = kind;
    ev.after = estimate_(j);
    if (event_count_ < params_) ++event_count_;
    ++total_events_;
  }

  // The reported estimate of parameter j: the joint sums' where one reports it, else the track's.
  void publish(int j) noexcept {
    if (!joints_.report(j, estimate_(j), sigma_(j))) {
      estimate_(j) = tracks_.estimate()(j);
      sigma_(j) = tracks_.sigma()(j);
    }
  }

  void publish_all() noexcept {
    for (int j = 0; j < params_; ++j)
      if (known_[j] == Known::kEstimated) publish(j);
  }

  Config config_;
  int n_;
  int params_;
  InputScreen<N, Scalar> screen_{};
  Windows windows_;
  typename Windows::Joints joints_;
  RobustTracks<Scalar, kParams, Capacity> tracks_{};
  ChangeDetector<Scalar, kParams> detector_{};
  detail::Storage<Known, kParams> known_{};
  Vector<Scalar, kParams> estimate_, sigma_, last_window_, last_variance_, pending_, pending_var_;
  int pending_next_ = 0;
  int budget_ = 0;
  detail::Storage<Event, kParams> events_{};
  int event_count_ = 0;
  long total_events_ = 0;
  long samples_ = 0;
  long results_ = 0;
};

/// The continuous estimator on weak-form windows (the default; allocates at construction).
template <int N, class Scalar = double, int Capacity = 64, int MaxStagger = 4>
using WeakFormContinuousEstimator = ContinuousEstimator<WeakFormSource<N, Scalar, MaxStagger>, Capacity>;

/// The continuous estimator on the paper's algebraic windows (no heap for a fixed N).
template <int N, class Scalar = double, int P = 8, int Capacity = 64, int MaxStagger = 4>
using AlgebraicContinuousEstimator = ContinuousEstimator<AlgebraicWindows<N, Scalar, P, MaxStagger>, Capacity>;

}  // namespace algid
