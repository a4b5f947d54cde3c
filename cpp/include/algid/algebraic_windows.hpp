#pragma once
/// @file algebraic_windows.hpp
/// The paper's windows as a window source of the continuous estimator: K (`stagger`)
/// ChainEstimators run side by side on windows of M samples (`window_s`), started M/K samples
/// apart, each reseeded when its window is full, so a window result arrives every M/K samples
/// (K = 4, 0.3 s: every 75 ms). With a force on some DOF only, a window scales the DOF without
/// force through their springs (ChainEstimator, "One force").
///
/// Prefilter. The accelerations and the forces pass through the same Butterworth low-pass
/// (`prefilter_hz`, default fs/20; order 4). Eq. 1 is linear and time-invariant, so the
/// filtered signals obey it with the same parameters, while the white noise above the cut-off,
/// which biases the windows (noise in the regressors: the masses come out low at 20 dB) and
/// scatters them, is gone; a force that is 0 stays exactly 0. The windows start once the
/// filter's start-up transient has decayed to 1e-6 (115 ms at 50 Hz).
///
/// Storage: MaxStagger ChainEstimator<N> and the prefilter (8 states per channel), inside the
/// object for a fixed N (allocated by the constructor for Dynamic): firmware without a heap
/// runs these windows.

#include "algid/chain_estimator.hpp"
#include "algid/continuous_error.hpp"
#include "algid/detail/prefilter.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

namespace algid {

/// The aggregation by information that exactly determined windows do not have: nothing is
/// summed, nothing reported (the tracks report every parameter).
template <class Scalar>
struct NoJointSums {
  void reset() noexcept {}
  bool step() noexcept { return false; }
  bool restart(int, double) noexcept { return false; }
  bool report(int, Scalar&, Scalar&) const noexcept { return false; }
  bool from_long(int) const noexcept { return false; }
  long screened() const noexcept { return 0; }
};

/// Configuration of AlgebraicWindows.
template <class Scalar>
struct AlgebraicWindowsConfig {
  Scalar dt = Scalar(1e-3);              ///< sample period [s]
  Boundary boundary = Boundary::kFixed;  ///< right end: wall or free (see ChainEstimator)
  ValidityRule<Scalar> validity{};       ///< validity rule of every window
  Scalar window_s = Scalar(0.3);         ///< window length M [s] (rounded to samples)
  int stagger = 4;                       ///< windows in flight K, started M/K apart (<= MaxStagger)
  /// independent fraction of the staggered window results, (0, 1] (they overlap)
  Scalar overlap_efficiency = Scalar(0.5);
  Scalar prefilter_hz = Scalar(-1);  ///< low-pass on accelerations and forces alike [Hz]; -1: 0.05 / dt, 0: off
  int prefilter_order = 4;           ///< Butterworth order of the prefilter: 2 or 4
};

/// The algebraic window source: staggered ChainEstimators behind a prefilter (see the file comment).
/// @tparam N number of DOF, or Dynamic. @tparam P quadrature points (see ChainEstimator).
/// @tparam MaxStagger most windows in flight.
template <int N, class Scalar = double, int P = 8, int MaxStagger = 4>
class AlgebraicWindows {
  static_assert(MaxStagger >= 1, "at least one window");
  static constexpr int kChannels = N == Dynamic ? Dynamic : 2 * N;

 public:
  /// The estimator run on each window.
  using Window = ChainEstimator<N, Scalar, P>;
  /// Scalar type of the samples and results.
  using ScalarType = Scalar;
  /// No joint sums: the tracks report every parameter.
  using Joints = NoJointSums<Scalar>;
  /// Configuration type.
  using Config = AlgebraicWindowsConfig<Scalar>;
  /// Number of DOF (Dynamic: given to the constructor).
  static constexpr int kDofs = N;
  /// Number of parameters of a window result (Dynamic: 3n+1).
  static constexpr int kParams = N == Dynamic ? Dynamic : 3 * N + 1;
  /// Most windows in flight.
  static constexpr int kMaxStagger = MaxStagger;
  /// Longest window [samples] (1e7: 2.8 h at 1 kHz).
  static constexpr long kMaxWindowSamples = 10000000;
  /// Lowest prefilter cut-off [cycles per sample] (1e-6: 1 mHz at 1 kHz; its start-up transient
  /// lasts about 6e6 samples).
  static constexpr double kMinPrefilterCycles = 1e-6;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static ContinuousConfigError validate(const Config& c, int n = N) noexcept {
    const ContinuousConfigError e = continuous_error(Window::validate(window_config(c), n));
    if (e != ContinuousConfigError::kNone) return e;
    if (!std::isfinite(c.window_s) || !(c.window_s > Scalar(0))) return ContinuousConfigError::kBadWindow;
    const Scalar samples = c.window_s / c.dt;
    if (!std::isfinite(samples) || samples > Scalar(kMaxWindowSamples)) return ContinuousConfigError::kBadWindow;
    const long m = std::lround(samples);
    if (m < static_cast<long>(P) + c.validity.min_samples) return ContinuousConfigError::kBadWindow;
    if (c.stagger < 1 || c.stagger > MaxStagger || c.stagger > m) return ContinuousConfigError::kBadStagger;
    if (!(c.overlap_efficiency > Scalar(0) && c.overlap_efficiency <= Scalar(1)))
      return ContinuousConfigError::kBadEfficiency;
    if (!std::isfinite(c.prefilter_hz) || (c.prefilter_hz < Scalar(0) && c.prefilter_hz != Scalar(-1)) ||
        (c.prefilter_hz > Scalar(0) && !(c.prefilter_hz * c.dt >= Scalar(kMinPrefilterCycles))) ||
        !(c.prefilter_hz * c.dt < Scalar(0.45)) || (c.prefilter_order != 2 && c.prefilter_order != 4))
      return ContinuousConfigError::kBadPrefilter;
    return ContinuousConfigError::kNone;
  }

  /// Configure (the configuration must be valid: see validate()). Allocates for N = Dynamic.
  AlgebraicWindows(const Config& config, int n)
      : config_(config),
        n_(n),
        windows_(make_windows(window_config(config), n, std::make_index_sequence<MaxStagger>{})) {
    filter_.configure_channels(2 * n_);
    io_.resize(2 * n_);
    result_.setZero(3 * n_ + 1);
    variance_.setConstant(3 * n_ + 1, std::numeric_limits<Scalar>::quiet_NaN());
    window_samples_ = std::lround(config_.window_s / config_.dt);
    const Scalar fc = config_.prefilter_hz < Scalar(0) ? Scalar(0.05) / config_.dt : config_.prefilter_hz;
    if (fc > Scalar(0)) {
      filter_.configure(fc, config_.dt, config_.prefilter_order);
      prefilter_hz_ = fc;
      // ln(1e6) / decay: the start-up transient is below 1e-6 of the signal when windows start
      settle_ = static_cast<long>(std::ceil(Scalar(13.815510557964274) / filter_.decay() / config_.dt));
    }
    for (int e = 0; e < config_.stagger; ++e) offset_[e] = window_samples_ * e / config_.stagger;
    restart();
  }

  /// The (absent) joint sums of these windows.
  Joints joints(int, int, Scalar, bool) const noexcept { return {}; }

  /// Drop the windows in flight and the prefilter's state; the next sample starts the schedule.
  /// @realtime no allocation, no throw
  void restart() noexcept {
    filter_.reset();
    for (int e = 0; e < MaxStagger; ++e) {
      windows_[e].reseed();
      phase_[e] = e < config_.stagger ? -(offset_[e] + settle_) : 0;
    }
  }

  /// Same as restart(): the windows keep nothing else.
  void reset() noexcept { restart(); }

  /// Consume one screened sample [m/s^2, N]; each window completed by it goes to
  /// `sink.window(result, variance)` (the variance NaN: an exactly determined window has none).
  /// @realtime no allocation, no throw, O(K N)
  template <class Sink>
  void update(const Scalar* accel, const Scalar* force, Sink& sink) noexcept {
    const Scalar* a = accel;
    const Scalar* f = force;
    if (prefilter_hz_ > Scalar(0)) {
      for (int i = 0; i < n_; ++i) {
        io_[i] = accel[i];
        io_[n_ + i] = force[i];
      }
      filter_.process(io_.data(), io_.data());  // cannot overflow: the screen bounds |x| by sqrt(max)
      a = io_.data();
      f = io_.data() + n_;
    }
    for (int e = 0; e < config_.stagger; ++e) {
      if (phase_[e] < 0) {
        ++phase_[e];
        continue;
      }
      windows_[e].update(a, f);
      if (++phase_[e] == window_samples_) {
        harvest(windows_[e]);
        sink.window(result_, variance_);
        windows_[e].reseed();
        phase_[e] = 0;
      }
    }
  }

  /// Window length M [samples].
  long window_samples() const noexcept { return window_samples_; }
  /// Samples between two window results (M/K).
  long hop_samples() const noexcept { return window_samples_ / config_.stagger; }
  /// Fewest samples between two window results.
  long min_spacing() const noexcept {
    long spacing = window_samples_;
    for (int e = 0; e < config_.stagger; ++e) {
      const long next = e + 1 < config_.stagger ? offset_[e + 1] : window_samples_ + offset_[0];
      spacing = std::min(spacing, next - offset_[e]);
    }
    return spacing;
  }
  /// Samples skipped after a (re)start while the prefilter settles (0 without prefilter).
  long settle_samples() const noexcept { return settle_; }
  /// Prefilter cut-off in force [Hz] (0: off).
  Scalar prefilter_hz() const noexcept { return prefilter_hz_; }
  /// Noise RMS estimate of channel c: -1, these windows estimate none.
  Scalar noise_rms(int) const noexcept { return Scalar(-1); }
  /// Misfit of the latest window: NaN, an exactly determined window has none.
  double misfit() const noexcept { return std::numeric_limits<double>::quiet_NaN(); }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 private:
  static typename Window::Config window_config(const Config& c) noexcept {
    typename Window::Config w;
    w.dt = c.dt;
    w.boundary = c.boundary;
    w.validity = c.validity;
    return w;
  }

  template <std::size_t... I>
  static std::array<Window, sizeof...(I)> make_windows(const typename Window::Config& c, int n,
                                                       std::index_sequence<I...>) {
    return {{((void)I, Window(c, n))...}};
  }

  // The window's result, fused as in ChainEstimator (NaN where it was not valid).
  void harvest(const Window& w) noexcept {
    for (int i = 0; i < n_; ++i) {
      result_(i) = w.mass()(i);
      result_(n_ + i) = w.damping()(i);
    }
    for (int j = 0; j <= n_; ++j) result_(2 * n_ + j) = w.stiffness()(j);
  }

  Config config_;
  int n_;
  std::array<Window, MaxStagger> windows_;
  detail::ButterworthLowpass<Scalar, kChannels> filter_{};
  detail::Storage<Scalar, kChannels> io_{};
  Scalar prefilter_hz_ = Scalar(0);
  long settle_ = 0;
  std::array<long, MaxStagger> phase_{};
  std::array<long, MaxStagger> offset_{};
  long window_samples_ = 0;
  Vector<Scalar, kParams> result_, variance_;
};

}  // namespace algid
