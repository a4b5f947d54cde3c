#pragma once
/// @file prefilter.hpp
/// Butterworth low-pass applied identically to every acceleration and force channel before
/// the algebraic windows (internals of ContinuousEstimator).
///
/// Why it is allowed: eq. 1 is linear and time-invariant, so the same LTI filter applied to
/// the accelerations and to the forces yields signals that obey eq. 1 with the same
/// parameters (once the filter's start-up transient has died out). Why it helps: white
/// measurement noise spreads over 0 .. fs/2 while a chain's response lives far below; the
/// filter removes the out-of-band noise, which is what biases (errors in the regressors)
/// and scatters the algebraic windows.

#include "algid/detail/storage.hpp"

#include <array>
#include <cmath>

namespace algid {
namespace detail {

/// Cascade of `Sections` second-order sections (transposed direct form II) on `Channels`
/// channels (or a run-time number: Channels = Dynamic, sized by configure_channels()); Butterworth
/// of order 2 * active sections, bilinear transform with pre-warping.
/// Storage: 5 coefficients per section and 2 states per section and channel.
template <class Scalar, int Channels, int Sections = 2>
class ButterworthLowpass {
 public:
  /// Design for cut-off `fc` [Hz] at sample period `dt` [s] and order 2 or 4 (not checked
  /// here: the owner validates). May be called in the configuration phase only.
  /// Size the states for `channels` channels (Channels, unless Dynamic). May be called in the
  /// configuration phase only.
  void configure_channels(int channels) {
    channels_ = fixed_or<Channels>(channels);
    state_.resize(channels_ * Sections);
    reset();
  }

  void configure(Scalar fc, Scalar dt, int order) noexcept {
    active_ = order / 2;
    const double pi = 3.14159265358979323846;
    const double k = std::tan(pi * static_cast<double>(fc) * static_cast<double>(dt));
    for (int s = 0; s < active_; ++s) {
      // pole pair s of the analogue prototype: Q = 1 / (2 cos(theta))
      const double theta = pi * (2.0 * s + 1.0) / (2.0 * order);
      const double q = 1.0 / (2.0 * std::cos(theta));
      const double norm = 1.0 / (1.0 + k / q + k * k);
      Coef& c = coef_[static_cast<std::size_t>(s)];
      c.b0 = static_cast<Scalar>(k * k * norm);
      c.b1 = static_cast<Scalar>(2.0 * k * k * norm);
      c.b2 = c.b0;
      c.a1 = static_cast<Scalar>(2.0 * (k * k - 1.0) * norm);
      c.a2 = static_cast<Scalar>((1.0 - k / q + k * k) * norm);
    }
    // Slowest pole's decay rate [1/s]: 2 pi fc sin(pi / (2 order)) for the analogue prototype.
    decay_ = static_cast<Scalar>(2.0 * pi * static_cast<double>(fc) * std::sin(pi / (2.0 * order)));
    reset();
  }

  /// Zero the states. @realtime no allocation, no throw
  void reset() noexcept { state_.fill({}); }

  /// Filter one sample of every channel, `in` -> `out` (may alias).
  /// @realtime no allocation, no throw
  void process(const Scalar* in, Scalar* out) noexcept {
    for (int ch = 0; ch < channels_; ++ch) {
      Scalar x = in[ch];
      for (int s = 0; s < active_; ++s) {
        const Coef& c = coef_[static_cast<std::size_t>(s)];
        auto& z = state_[ch * Sections + s];
        const Scalar y = c.b0 * x + z[0];
        z[0] = c.b1 * x - c.a1 * y + z[1];
        z[1] = c.b2 * x - c.a2 * y;
        x = y;
      }
      out[ch] = x;
    }
  }

  /// Decay rate of the slowest pole [1/s] (the start-up transient falls as exp(-decay t)).
  Scalar decay() const noexcept { return decay_; }

 private:
  struct Coef {
    Scalar b0 = Scalar(1), b1 = Scalar(0), b2 = Scalar(0), a1 = Scalar(0), a2 = Scalar(0);
  };
  std::array<Coef, Sections> coef_{};
  Storage<std::array<Scalar, 2>, Channels == Dynamic ? Dynamic : Channels * Sections> state_{};
  int channels_ = Channels == Dynamic ? 0 : Channels;
  int active_ = 0;
  Scalar decay_ = Scalar(0);
};

}  // namespace detail
}  // namespace algid
