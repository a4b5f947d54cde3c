#pragma once
/// @file weak_form_weights.hpp
/// The GLS weights of the weak-form windows, W = Sigma^-1 over all n F rows, refreshed in the
/// background from the owner's running estimate (see weak_form.hpp for the covariance Sigma).
///
/// The equation errors of neighbouring DOFs share channels, so Sigma is block pentadiagonal
/// (blocks of F x F). A refresh runs in stages, in steps of at most about 9 F^2 multiply-adds,
/// as many per sample as a budget of 6 F^2 allows, so no sample pays for a whole refresh:
///   1. Sigma block by block from the model, into the lower triangle of the factor;
///   2. its Cholesky factor in place, column by column (left-looking, within the band: fill-in
///      stays inside it); not positive definite: the old weights are kept;
///   3. W column by column, one row block per step (forward, then backward substitution);
///   4. the traces <W_ij, G_de> of the bias term, block by block;
///   5. W swapped in, between two windows only.
/// The first refresh after reset() keeps only the diagonal blocks (band 0: each DOF's rows
/// weighted alone, about n^2 times less work) so that weighted windows start early; the
/// following ones use the full covariance.

#include "algid/types.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace algid {
namespace detail {

/// True if DOF i of an n-DOF chain has a spring to its right (a neighbour or the right wall).
inline bool right_spring(int i, int n, Boundary boundary) noexcept {
  return n > 1 && (i + 1 < n || boundary == Boundary::kFixed);
}

/// Weights W = Sigma^-1 of the weak-form rows and the traces <W_ij, G_de> of the bias term,
/// with the Gram matrices G_de = dt^2 sum psi^(d) psi^(e)^T of the test functions.
/// Storage: three R x R matrices (W in force, the next W, the Cholesky factor), R = n F.
class WeakFormWeights {
 public:
  using MatD = Eigen::MatrixXd;
  using VecD = Eigen::VectorXd;

  /// Configure for n DOF, F rows per DOF, windows of L samples of dt [s]; `enabled` false:
  /// never refreshed (unweighted). Allocates every buffer and computes the Gram matrices.
  void configure(int n, int F, long L, double dt, Boundary boundary, bool enabled) {
    n_ = n;
    F_ = F;
    R_ = n * F;
    params_ = 3 * n + 1;
    boundary_ = boundary;
    enabled_ = enabled;
    weight_.setZero(R_, R_);
    chol_.setZero(R_, R_);
    wnext_.setZero(R_, R_);
    traces_.setZero(n_ * 5 * 9);
    next_traces_.setZero(n_ * 5 * 9);
    identity_traces_.setZero(9);
    model_.setConstant(params_, std::numeric_limits<double>::quiet_NaN());
    gram(L, dt);
    reset();
  }

  /// Back to unweighted (W = I), no model, no refresh in progress. @realtime no allocation, no throw
  void reset() noexcept {
    weight_.setIdentity();
    weighted_ = false;
    full_ = false;
    model_.setConstant(std::numeric_limits<double>::quiet_NaN());
    stage_ = 0;
    pos_ = 0;
    sub_ = 0;
  }

  /// Running parameters (m, c, k packed, 3n+1) that the weights are computed from.
  /// @realtime no allocation, no throw
  template <class Scalar>
  void set_model(const Scalar* theta) noexcept {
    for (int j = 0; j < params_; ++j) model_(j) = static_cast<double>(theta[j]);
  }

  /// Advance the refresh by a budget of 6 F^2 multiply-adds. `noise.variance(c)` gives the
  /// noise variance of channel c (accelerations 0..n-1, forces n..2n-1); the new weights are
  /// swapped in only while `window_pending` is false. @realtime no allocation, no throw
  template <class Noise>
  void refresh(const Noise& noise, bool window_pending) noexcept {
    if (!enabled_) return;
    const double budget = 6.0 * F_ * F_;
    double spent = 0.0;
    while (spent < budget) {
      const double cost = step(noise, window_pending);
      if (cost < 0.0) return;  // waiting: no model yet, or a window in progress
      spent += cost + 1.0;
    }
  }

  /// The weights in force (R x R; the identity until the first refresh).
  const MatD& matrix() const noexcept { return weight_; }
  /// True once every DOF's rows are weighted by a covariance from the running estimate.
  bool weighted() const noexcept { return weighted_; }
  /// True if the weights in force come from the full covariance (not the diagonal blocks).
  bool full() const noexcept { return full_; }

  /// Subtract the regressor-noise bias E[N^T W N] from a window's normal matrix (3n+1 square):
  /// the noise of acceleration channel c loads the columns (DOF row block, parameter,
  /// derivative order, sign) listed here, and E[N^T W N](p, q) = sum_c s_c^2 sum a_p a_q
  /// <W_ij, G_de>, with W the weights in force if `weighted` (the window's rows were
  /// weighted), else the identity. @realtime no allocation, no throw
  template <class Noise>
  void subtract_bias(MatD& normal, const Noise& noise, bool weighted) const noexcept {
    const int n = n_;
    for (int c = 0; c < n; ++c) {
      const double s2 = noise.variance(c);
      if (!(s2 > 0.0)) continue;
      int blk[6], par[6], ord[6], cnt = 0;
      double sgn[6];
      const auto add = [&](int b, int p, int d, double a) {
        blk[cnt] = b, par[cnt] = p, ord[cnt] = d, sgn[cnt] = a, ++cnt;
      };
      add(c, c, 2, 1.0);
      add(c, n + c, 1, -1.0);
      add(c, 2 * n + c, 0, 1.0);
      if (right(c)) add(c, 2 * n + c + 1, 0, 1.0);
      if (c > 0) add(c - 1, 2 * n + c, 0, -1.0);           // DOF c-1's right spring
      if (c + 1 < n) add(c + 1, 2 * n + c + 1, 0, -1.0);  // DOF c+1's left spring
      for (int a = 0; a < cnt; ++a)
        for (int b = 0; b < cnt; ++b)
          normal(par[a], par[b]) -= s2 * sgn[a] * sgn[b] * trace(blk[a], blk[b], ord[a], ord[b], weighted);
    }
  }

 private:
  static constexpr double kTwoPi = 6.283185307179586476925;

  // Gram matrices of the test functions and their derivatives (configuration phase).
  void gram(long L, double dt) {
    const double W = static_cast<double>(L) * dt;
    MatD psi[3];
    for (auto& p : psi) p.setZero(F_, L);
    for (long l = 0; l < L; ++l) {
      const double t = static_cast<double>(l) * dt;
      const double a = 3.14159265358979323846 / W;
      const double s = std::sin(a * t), co = std::cos(a * t);
      const double w0 = s * s * s * s, w1 = 4 * s * s * s * co * a;
      const double w2 = a * a * 4 * (3 * s * s * co * co - s * s * s * s);
      for (int f = 0; f < F_; ++f) {
        const int q = (f + 1) / 2;
        const bool sine = f > 0 && f % 2 == 0;
        const double om = kTwoPi * q / W;
        const double g0 = sine ? std::sin(om * t) : std::cos(om * t);
        const double g1 = sine ? om * std::cos(om * t) : -om * std::sin(om * t);
        const double g2 = -om * om * g0;
        psi[0](f, l) = w0 * g0;
        psi[1](f, l) = w1 * g0 + w0 * g1;
        psi[2](f, l) = w2 * g0 + 2 * w1 * g1 + w0 * g2;
      }
    }
    const double d2 = dt * dt;
    for (int d = 0; d < 3; ++d)
      for (int e = 0; e < 3; ++e) {
        gram_[3 * d + e] = d2 * psi[d] * psi[e].transpose();
        identity_traces_(3 * d + e) = gram_[3 * d + e].trace();
      }
  }

  bool right(int i) const noexcept { return right_spring(i, n_, boundary_); }

  // <W_ij, G_de> of the weights in force (|i - j| <= 2), or <I_ij, G_de> if not `weighted`.
  double trace(int i, int j, int d, int e, bool weighted) const noexcept {
    if (!weighted) return i == j ? identity_traces_(3 * d + e) : 0.0;
    return traces_(((i * 5) + (j - i + 2)) * 9 + 3 * d + e);
  }

  // Noise loading of DOF i's equation error on acceleration channel c, derivative order d:
  // m_i (d = 2), -c_i (d = 1), the stiffness matrix entry K_ic (d = 0).
  double loading(int i, int c, int d) const noexcept {
    const int n = n_;
    const double kl = model_(2 * n + i), kr = right(i) ? model_(2 * n + i + 1) : 0.0;
    if (c == i) return d == 2 ? model_(i) : d == 1 ? -model_(n + i) : kl + kr;
    if (d != 0) return 0.0;
    if (c == i - 1) return -kl;
    if (c == i + 1) return -kr;
    return 0.0;
  }

  // One step; its cost in multiply-adds, or -1 if the refresh cannot advance in this sample.
  template <class Noise>
  double step(const Noise& noise, bool window_pending) noexcept {
    switch (stage_) {
      case 0:
        if (!usable_model(noise)) return -1.0;
        band_ = weighted_ ? 2 : 0;
        stage_ = 1;
        pos_ = 0;
        return 0.0;
      case 1: return sigma_step(noise);
      case 2: return cholesky_step();
      case 3: return inverse_step();
      case 4: return traces_step();
      default:
        if (window_pending) return -1.0;  // never change the weights under a window in progress
        weight_.swap(wnext_);
        traces_.swap(next_traces_);
        weighted_ = true;
        full_ = band_ == 2 || n_ == 1;
        stage_ = 0;
        return -1.0;
    }
  }

  // Positive finite masses, finite dampers and springs, and noise on every acceleration
  // (noise-free: the weights do not matter).
  template <class Noise>
  bool usable_model(const Noise& noise) const noexcept {
    for (int i = 0; i < n_; ++i) {
      if (!(model_(i) > 0.0) || !std::isfinite(model_(i)) || !std::isfinite(model_(n_ + i))) return false;
      if (!(noise.variance(i) > 0.0)) return false;
    }
    for (int j = 2 * n_; j < params_; ++j)
      if (!std::isfinite(model_(j)) && (j < params_ - 1 || right(n_ - 1))) return false;
    return true;
  }

  // Block (i, j) of Sigma, i >= j >= i - 2 (zero outside the band), and the zero blocks left
  // of the band in row i.
  template <class Noise>
  double sigma_step(const Noise& noise) noexcept {
    const int F = F_, i = pos_ / 3, j = i - pos_ % 3;
    double cost = 0.0;
    if (j == i && i > 2) chol_.block(i * F, 0, F, (i - 2) * F).setZero();
    if (j >= 0) {
      auto block = chol_.block(i * F, j * F, F, F);
      block.setZero();
      for (int c = std::max(0, i - 1); c <= std::min(n_ - 1, j + 1) && i - j <= band_; ++c) {
        const double s2 = noise.variance(c);
        for (int d = 0; d < 3; ++d)
          for (int e = 0; e < 3; ++e) {
            const double a = s2 * loading(i, c, d) * loading(j, c, e);
            if (a == 0.0) continue;
            block.noalias() += a * gram_[3 * d + e];
            cost += F * F;
          }
      }
      if (i == j) block.noalias() += noise.variance(n_ + i) * gram_[8];
    }
    if (++pos_ == 3 * n_) {
      stage_ = 2;
      pos_ = 0;
    }
    return cost + F * F;
  }

  // Column j of the Cholesky factor, in place; rows and columns within the band (fill-in stays
  // inside it). Not positive definite: keep the old weights.
  double cholesky_step() noexcept {
    const int F = F_, j = pos_, b = j / F;
    const int k0 = std::max(0, b - band_) * F, r1 = std::min(R_, (b + band_ + 1) * F);
    auto lj = chol_.row(j).segment(k0, j - k0);
    const double d = chol_(j, j) - lj.squaredNorm();
    if (!(d > 0.0) || !std::isfinite(d)) {
      stage_ = 0;
      return -1.0;
    }
    const double root = std::sqrt(d);
    chol_(j, j) = root;
    const int below = r1 - j - 1;
    if (below > 0) {
      auto col = chol_.col(j).segment(j + 1, below);
      col.noalias() -= chol_.block(j + 1, k0, below, j - k0) * lj.transpose();
      col /= root;
    }
    if (++pos_ == R_) {
      stage_ = 3;
      pos_ = 0;
      sub_ = 0;
    }
    return static_cast<double>(below + 1) * (j - k0 + 1);
  }

  // Column j of W = (L L^T)^-1, one row block per step: forward from j's block down, then
  // backward from the last block up (within j's block only while the band is 0).
  double inverse_step() noexcept {
    const int F = F_, j = pos_, bj = j / F;
    const int last = band_ > 0 ? n_ - 1 : bj, first = band_ > 0 ? 0 : bj;
    const int forward = last - bj + 1, steps = forward + last - first + 1;
    auto w = wnext_.col(j);
    const auto reach = [&](int k) { return std::min(R_, (k / F + band_ + 1) * F); };
    double cost = 0.0;
    if (sub_ < forward) {
      const int b = bj + sub_;
      if (sub_ == 0) {
        w.setZero();
        w(j) = 1.0;
      }
      for (int k = std::max(j, b * F); k < (b + 1) * F; ++k) {
        w(k) /= chol_(k, k);
        const int end = reach(k);
        if (end > k + 1) w.segment(k + 1, end - k - 1).noalias() -= w(k) * chol_.col(k).segment(k + 1, end - k - 1);
        cost += end - k;
      }
    } else {
      const int b = last - (sub_ - forward);
      for (int r = (b + 1) * F - 1; r >= b * F; --r) {
        const int end = reach(r);
        double x = w(r);
        if (end > r + 1) x -= chol_.col(r).segment(r + 1, end - r - 1).dot(w.segment(r + 1, end - r - 1));
        w(r) = x / chol_(r, r);
        cost += end - r;
      }
    }
    if (++sub_ == steps) {
      sub_ = 0;
      if (++pos_ == R_) {
        stage_ = 4;
        pos_ = 0;
      }
    }
    return cost;
  }

  // <W_ij, G_de> for one block pair (i, j = i - 2 .. i + 2; zero outside the band).
  double traces_step() noexcept {
    const int F = F_, i = pos_ / 5, o = pos_ % 5, j = i + o - 2;
    const bool inside = j >= 0 && j < n_ && std::abs(i - j) <= band_;
    for (int de = 0; de < 9; ++de)
      next_traces_((i * 5 + o) * 9 + de) = inside ? wnext_.block(i * F, j * F, F, F).cwiseProduct(gram_[de]).sum()
                                                  : 0.0;
    if (++pos_ == 5 * n_) stage_ = 5;
    return inside ? 9.0 * F * F : 1.0;
  }

  int n_ = 0, F_ = 0, R_ = 0, params_ = 0;
  Boundary boundary_ = Boundary::kFixed;
  bool enabled_ = true;
  MatD weight_, chol_, wnext_;  // W in force, the Cholesky factor (holds Sigma first), the next W
  MatD gram_[9];
  VecD traces_, next_traces_, identity_traces_, model_;
  int stage_ = 0, pos_ = 0, sub_ = 0, band_ = 0;  // refresh stage 0..5, its column or block, its row block
  bool weighted_ = false, full_ = false;
};

}  // namespace detail
}  // namespace algid
