#pragma once
/// @file dropout.hpp
/// Sensor dropouts that are finite numbers: a channel stuck at one value, a channel clipped at
/// its range. A real accelerometer's noise changes its reading every sample, so a run of
/// bit-identical samples on a channel that has moved before is a dead sensor, a frozen
/// acquisition buffer or a saturated amplifier, not a measurement; fed to the estimator it
/// would read as a sudden change of the parameters.
///
/// Rules, per channel, over the samples given to check():
///   - stuck: the channel has taken two different values before, and its value has repeated
///     exactly for `stuck_samples` samples in a row (0: rule off);
///   - clipped: the value has repeated exactly for `clip_samples` samples in a row at the
///     largest or smallest value the channel has taken (0: rule off).
/// A run is reported from the sample that completes it until the value changes.
///
/// Storage: three scalars, one count and one flag per channel (fixed for Channels >= 0,
/// allocated by configure() for Dynamic).
#include "algid/detail/storage.hpp"

#include <limits>

namespace algid {

/// What check() found in a sample.
enum class Dropout : int {
  kNone = 0,     ///< every channel is moving
  kStuck = 1,    ///< a channel repeats one value (and has moved before)
  kClipped = 2,  ///< a channel repeats its largest or smallest value so far
};

namespace detail {

template <class Scalar, int Channels>
class DropoutDetector {
 public:
  /// Configure for `channels` channels. May allocate (Channels == Dynamic).
  void configure(int channels, long stuck_samples, long clip_samples) {
    channels_ = channels;
    stuck_ = stuck_samples;
    clip_ = clip_samples;
    for (auto* s : {&last_, &high_, &low_}) s->resize(channels);
    run_.resize(channels);
    moved_.resize(channels);
    reset();
  }

  /// Forget every channel's history.
  /// @realtime no allocation, no throw
  void reset() noexcept {
    last_.fill(std::numeric_limits<Scalar>::quiet_NaN());
    high_.fill(-std::numeric_limits<Scalar>::infinity());
    low_.fill(std::numeric_limits<Scalar>::infinity());
    run_.fill(0);
    moved_.fill(false);
  }

  /// Learn one sample of every channel (finite values) and say whether any channel is stuck or
  /// clipped now; `channel` gets the first such channel (0-based), else -1.
  /// @realtime no allocation, no throw, O(channels)
  Dropout check(const Scalar* x, int& channel) noexcept {
    Dropout found = Dropout::kNone;
    channel = -1;
    for (int i = 0; i < channels_; ++i) {
      const Scalar v = x[i];
      if (v == last_[i]) {
        ++run_[i];
      } else {
        moved_[i] = moved_[i] || last_[i] == last_[i];  // a second distinct value
        run_[i] = 1;
        last_[i] = v;
      }
      if (v > high_[i]) high_[i] = v;
      if (v < low_[i]) low_[i] = v;
      const bool extreme = moved_[i] && (v == high_[i] || v == low_[i]);
      Dropout here = Dropout::kNone;
      if (clip_ > 0 && extreme && run_[i] >= clip_)
        here = Dropout::kClipped;
      else if (stuck_ > 0 && moved_[i] && run_[i] >= stuck_)
        here = Dropout::kStuck;
      if (here != Dropout::kNone && found == Dropout::kNone) {
        found = here;
        channel = i;
      }
    }
    return found;
  }

 private:
  int channels_ = 0;
  long stuck_ = 0;
  long clip_ = 0;
  Storage<Scalar, Channels> last_{}, high_{}, low_{};
  Storage<long, Channels> run_{};
  Storage<bool, Channels> moved_{};
};

}  // namespace detail
}  // namespace algid
