#pragma once
/// @file weak_form_noise.hpp
/// The noise RMS per channel that the weak-form windows weight and correct with: given
/// (accel_noise, force_noise >= 0) or estimated from the fourth difference of the raw signal.
/// For white noise of RMS s the fourth difference x_t - 4 x_{t-1} + 6 x_{t-2} - 4 x_{t-3} + x_{t-4}
/// has variance 70 s^2; a band-limited response at 20 Hz of 1 kHz leaks (2 pi 0.02)^4 of its
/// amplitude into it. The squared differences are exponentially forgotten.

#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace algid {
namespace detail {

/// Noise variance of 2n channels (accelerations 0..n-1 [m/s^2], forces n..2n-1 [N]) from a
/// forgotten mean of squared fourth differences, or the given RMS.
/// @tparam Scalar type of the given RMS. @tparam Channels 2n, or Dynamic.
template <class Scalar, int Channels>
class FourthDifferenceNoise {
 public:
  /// Configure for n DOF: sample period [s], forgetting time constant [s], the given RMS of
  /// the accelerations [m/s^2] and forces [N] (-1: estimated). Allocates (Channels == Dynamic).
  void configure(int n, double dt, double horizon_s, Scalar accel_noise, Scalar force_noise) {
    n_ = n;
    keep_ = 1.0 - dt / horizon_s;
    accel_noise_ = accel_noise;
    force_noise_ = force_noise;
    noise_.resize(2 * n);
    history_.resize(2 * n);
    reset();
  }

  /// Forget the estimate and the signal history. @realtime no allocation, no throw
  void reset() noexcept {
    for (int c = 0; c < 2 * n_; ++c) {
      noise_[c] = Sum{};
      history_[c] = History{};
    }
  }

  /// Forget the signal history only (no differences across a gap). @realtime no allocation, no throw
  void restart() noexcept {
    for (int c = 0; c < 2 * n_; ++c) history_[c].count = 0;
  }

  /// One sample x of channel c. The estimate starts from the median of the first 64 squared
  /// differences (one absurd sample among them does not set it); non-finite ones are skipped;
  /// later ones enter clipped at kClip times the mean so far (for white noise a squared fourth
  /// difference over its mean is chi^2_1: beyond 30 once in 2.5e7), so one absurd sample moves
  /// it by at most 30 dt / noise_horizon_s (0.3 %), while a real rise of the noise is followed
  /// at e-fold per noise_horizon_s / 29 (0.34 s). @realtime no allocation, no throw
  void observe(int c, double x) noexcept {
    History& h = history_[c];
    if (h.count == 4) {
      const double d4 = x - 4 * h.x[3] + 6 * h.x[2] - 4 * h.x[1] + h.x[0];
      Sum& s = noise_[c];
      double q = d4 * d4;
      if (std::isfinite(q)) {
        if (s.started == kStart && s.sum > 0.0) q = std::min(q, kClip * s.sum / s.weight);
        s.sum = keep_ * s.sum + q;
        s.weight = keep_ * s.weight + 1.0;
        if (s.started < kStart) {
          s.start[static_cast<std::size_t>(s.started++)] = q;
          if (s.started == kStart) {
            auto mid = s.start.begin() + kStart / 2;
            std::nth_element(s.start.begin(), mid, s.start.end());
            s.sum = s.weight * *mid / 0.4549;  // median of chi^2_1 = 0.4549 of its mean
          }
        }
      }
    }
    h.x[0] = h.x[1];
    h.x[1] = h.x[2];
    h.x[2] = h.x[3];
    h.x[3] = x;
    h.count = std::min(h.count + 1, 4);
  }

  /// Noise variance of channel c (the given RMS squared, or the estimate; 0 before any)
  /// [m^2/s^4 or N^2]. @realtime no allocation, no throw
  double variance(int c) const noexcept {
    const Scalar given = c < n_ ? accel_noise_ : force_noise_;
    if (given >= Scalar(0)) return static_cast<double>(given) * static_cast<double>(given);
    const Sum& s = noise_[c];
    return s.weight > 0.0 ? s.sum / (70.0 * s.weight) : 0.0;
  }

 private:
  static constexpr int kStart = 64;     // fourth differences whose median starts the estimate
  static constexpr double kClip = 30.0;  // clip of a later one, times the running mean
  struct Sum {
    double sum = 0.0;                   // forgotten sum of squared fourth differences
    double weight = 0.0;                // forgotten count
    std::array<double, kStart> start{};  // the first squared fourth differences
    int started = 0;
  };
  struct History {
    double x[4] = {0.0, 0.0, 0.0, 0.0};
    int count = 0;
  };

  int n_ = 0;
  double keep_ = 1.0;  // forgetting factor per sample
  Scalar accel_noise_ = Scalar(-1), force_noise_ = Scalar(-1);
  Storage<Sum, Channels> noise_{};
  Storage<History, Channels> history_{};
};

}  // namespace detail
}  // namespace algid
