#pragma once
/// @file weak_form_sums.hpp
/// The Fourier sums behind the weak-form rows (see weak_form.hpp): per channel the plain sums
/// X_j = sum_t x e^{i w_j t} dt, j = 0 .. Q+2, w_j = 2 pi j / W, accumulated in K hop blocks of
/// W/K samples so that K staggered windows share them; a window's sums are its K newest blocks,
/// and its rows int psi_q^(d) x are five of them each (psi_q = sin^4(pi t / W) e^{i w_q t}).

#include <Eigen/Core>

#include <cmath>
#include <complex>

namespace algid {
namespace detail {

/// Hop-block Fourier sums of 2n channels (accelerations 0..n-1, forces n..2n-1) and the
/// weak-form rows of the window they complete.
/// Storage: K J 2n complex bins and J 2n of the window (J = Q + 3).
class WeakFormSums {
 public:
  /// Configure for n DOF, windows of L samples of dt [s] in K hop blocks, Q harmonics.
  /// Allocates every buffer.
  void configure(int n, long L, int K, int Q, double dt) {
    n_ = n;
    L_ = L;
    K_ = K;
    H_ = L / K;
    Q_ = Q;
    J_ = Q + 3;
    dt_ = dt;
    z_.resize(J_);
    bins_.setZero(J_, 2 * n * K_);
    seg_.setZero(J_, 2 * n);
    restart();
  }

  /// Drop every block. @realtime no allocation, no throw
  void restart() noexcept {
    bins_.setZero();
    phase_ = 0;
    in_hop_ = 0;
    hops_ = 0;
  }

  /// Add one sample of the accelerations [m/s^2] and forces [N]. Returns true when it completes
  /// a window (its sums are then ready for rows()). @realtime no allocation, no throw; O(J 2n)
  template <class Scalar>
  bool add(const Scalar* accel, const Scalar* force) noexcept {
    const int n = n_;
    // Fourier sums of this hop block: phasors e^{i 2 pi j phase / L}, j = 0 .. J-1.
    const double angle = kTwoPi * static_cast<double>(phase_) / static_cast<double>(L_);
    const Complex z1(std::cos(angle), std::sin(angle));
    z_(0) = Complex(dt_, 0.0);
    for (int j = 1; j < J_; ++j) z_(j) = z_(j - 1) * z1;
    const int block = static_cast<int>(hops_ % K_);
    for (int c = 0; c < 2 * n; ++c) {
      const double x = c < n ? static_cast<double>(accel[c]) : static_cast<double>(force[c - n]);
      bins_.col(block * 2 * n + c) += x * z_;
    }
    if (++phase_ == L_) phase_ = 0;
    bool window = false;
    if (++in_hop_ == H_) {
      in_hop_ = 0;
      ++hops_;
      if (hops_ >= K_) {
        close_window();
        window = true;
      }
      bins_.middleCols(static_cast<int>(hops_ % K_) * 2 * n, 2 * n).setZero();  // the oldest block restarts
    }
    return window;
  }

  /// Rows of the latest window into `rows` (F x 4n, F = 2Q + 1: real and imaginary parts of the
  /// harmonics 0..Q): columns 0..n-1 int psi a (d = 0), n..2n-1 d = 1, 2n..3n-1 d = 2,
  /// 3n..4n-1 int psi'' u. @realtime no allocation, no throw
  void rows(Eigen::MatrixXd& rows) const noexcept {
    const double W = static_cast<double>(L_) * dt_;
    const int n = n_;
    for (int q = 0; q <= Q_; ++q) {
      for (int c = 0; c < 2 * n; ++c) {
        Complex r[3] = {Complex(0.0, 0.0), Complex(0.0, 0.0), Complex(0.0, 0.0)};
        for (int k = -2; k <= 2; ++k) {
          const Complex x = kTaper[k + 2] * bin(q + k, c);
          const Complex iw(0.0, kTwoPi * (q + k) / W);
          r[0] += x;
          r[1] += iw * x;
          r[2] += iw * iw * x;
        }
        for (int d = 0; d < 3; ++d) {
          if (c >= n && d < 2) continue;
          const int col = c < n ? d * n + c : 3 * n + (c - n);
          const Complex v = c < n ? r[d] : r[2];
          rows(2 * q == 0 ? 0 : 2 * q - 1, col) = v.real();
          if (q > 0) rows(2 * q, col) = v.imag();
        }
      }
    }
  }

  /// Samples between two windows.
  long hop_samples() const noexcept { return H_; }

 private:
  using Complex = std::complex<double>;
  using MatC = Eigen::Matrix<Complex, Eigen::Dynamic, Eigen::Dynamic>;
  using VecC = Eigen::Matrix<Complex, Eigen::Dynamic, 1>;
  static constexpr double kTwoPi = 6.283185307179586476925;
  // sin^4(x) = 3/8 - cos(2x)/2 + cos(4x)/8: coefficients of e^{i 2 pi k t / W}, k = -2..2.
  static constexpr double kTaper[5] = {1.0 / 16, -1.0 / 4, 3.0 / 8, -1.0 / 4, 1.0 / 16};

  // The K newest hop blocks form a window: sum them, shift the phasors to its start.
  void close_window() noexcept {
    const int C = 2 * n_;
    seg_.setZero();
    for (int b = 0; b < K_; ++b) seg_ += bins_.middleCols(b * C, C);
    // The window started L - K H = 0 samples of phase ago modulo L, i.e. at phase_ (mod L).
    const double angle = -kTwoPi * static_cast<double>(phase_) / static_cast<double>(L_);
    const Complex r(std::cos(angle), std::sin(angle));
    Complex rot(1.0, 0.0);
    for (int j = 0; j < J_; ++j) {
      seg_.row(j) *= rot;
      rot *= r;
    }
  }

  // Bin j of channel c with X_{-j} = conj(X_j).
  Complex bin(int j, int c) const noexcept { return j >= 0 ? seg_(j, c) : std::conj(seg_(-j, c)); }

  int n_ = 0, K_ = 1, Q_ = 0, J_ = 0;
  long L_ = 0, H_ = 0;
  double dt_ = 0.0;
  long phase_ = 0, in_hop_ = 0, hops_ = 0;  // sample within the window, within the hop; hops since restart
  VecC z_;
  MatC bins_, seg_;
};

}  // namespace detail
}  // namespace algid
