#pragma once
/// @file input_screen.hpp
/// The input screen of the continuous estimator: which samples reach the windows. A sample is
/// refused when it is not finite (or not finite squared), when it lies beyond `outlier_ratio`
/// times its channel's running RMS (kBadInput), or when an acceleration is stuck or clipped
/// (kDropout, detail/dropout.hpp).
///
/// Storage: two running mean squares per DOF and the dropout detector's state (inside the
/// object for a fixed N; allocated by configure() for Dynamic).

#include "algid/detail/dropout.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <cmath>

namespace algid {

/// Configuration of the InputScreen.
template <class Scalar>
struct ScreenConfig {
  /// A finite sample beyond this many times its channel's running RMS (time constant one
  /// window, measured once a window of samples has passed) is treated as bad input; 0: off.
  Scalar outlier_ratio = Scalar(1e8);
  /// An acceleration that has moved and then repeats one value exactly for this many samples in
  /// a row is a dead sensor (detail/dropout.hpp): its samples are discarded like bad input and
  /// update() returns kDropout; 0: off. Short, because the windows harvested before a run is
  /// recognised keep its frozen samples (tests/test_dropouts.py; docs/reliability.md, sensor
  /// dropouts).
  long stuck_samples = 16;
  /// An acceleration that repeats its largest or smallest value so far for this many samples in
  /// a row is clipped: discarded the same way; 0: off.
  long clip_samples = 3;

  /// True if the fields are in range: outlier_ratio 0 or finite and > 1, the dropout runs 0 or >= 2.
  bool valid_outlier_ratio() const noexcept {
    return std::isfinite(outlier_ratio) && (outlier_ratio == Scalar(0) || outlier_ratio > Scalar(1));
  }
  bool valid_dropout() const noexcept {
    return stuck_samples >= 0 && stuck_samples != 1 && clip_samples >= 0 && clip_samples != 1;
  }
};

/// The input screen of an N-DOF chain's accelerations and forces (see the file comment).
/// @tparam N number of DOF, or Dynamic (given to configure()).
template <int N, class Scalar = double>
class InputScreen {
  static constexpr int kChannels = N == Dynamic ? Dynamic : 2 * N;

 public:
  /// Configuration type.
  using Config = ScreenConfig<Scalar>;

  /// Size and configure; `window_samples` is the time constant of the running mean squares and
  /// the samples before the outlier test is armed. Allocates for N = Dynamic.
  void configure(int n, long window_samples, const Config& config) {
    n_ = n;
    window_samples_ = window_samples;
    config_ = config;
    mean_square_.resize(2 * n);
    dropout_.configure(n, config.stuck_samples, config.clip_samples);
    reset();
  }

  /// Forget the scales and the dropout runs. @realtime no allocation, no throw
  void reset() noexcept {
    mean_square_.fill(Scalar(0));
    accepted_ = 0;
    out_of_range_ = 0;
    dropout_.reset();
    in_dropout_ = false;
    dropout_samples_ = 0;
    dropout_runs_ = 0;
    last_dropout_ = Dropout::kNone;
    dropout_channel_ = -1;
  }

  /// kOk if the sample may reach the windows, kBadInput (not finite, or an outlier) or kDropout
  /// (an acceleration stuck or clipped) if not. @realtime no allocation, no throw, O(N)
  Status check(const Scalar* accel, const Scalar* force) noexcept {
    if (!plausible(accel, force)) return Status::kBadInput;
    if (dropped(accel)) return Status::kDropout;
    return Status::kOk;
  }

  /// Samples discarded as dropouts since configure() or reset().
  long dropout_samples() const noexcept { return dropout_samples_; }
  /// Runs of dropout samples since configure() or reset().
  long dropout_runs() const noexcept { return dropout_runs_; }
  /// Kind of the latest dropout run (kNone: none yet).
  Dropout last_dropout() const noexcept { return last_dropout_; }
  /// Acceleration channel of the latest dropout run (0-based; -1: none).
  int dropout_channel() const noexcept { return dropout_channel_; }

 private:
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

  // A stuck or clipped acceleration; counts a new run when the previous sample was not one.
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

  Config config_{};
  int n_ = 0;
  long window_samples_ = 1;
  detail::Storage<Scalar, kChannels> mean_square_{};  // running mean square of every raw channel
  long accepted_ = 0;      // plausible samples since reset() or a new level
  long out_of_range_ = 0;  // finite samples out of range in a row
  detail::DropoutDetector<Scalar, N> dropout_{};
  bool in_dropout_ = false;
  long dropout_samples_ = 0;
  long dropout_runs_ = 0;
  Dropout last_dropout_ = Dropout::kNone;
  int dropout_channel_ = -1;
};

}  // namespace algid
