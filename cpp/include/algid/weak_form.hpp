#pragma once
/// @file weak_form.hpp
/// Weak-form (modulating-function) windows: every window of W seconds gives a generalised
/// least-squares solution for all 3n+1 parameters of the chain from all of its algebraic rows,
/// corrected for the bias that noise in the regressors causes.
///
/// Rows. For a test function psi that vanishes with psi' at both ends of the window, eq. 1
/// times psi'' integrated by parts twice gives, for DOF i (x measured only through a = x''),
///
///   m_i int psi'' a_i - c_i int psi' a_i + k_i int psi (a_i - a_{i-1})
///                                        + k_{i+1} int psi (a_i - a_{i+1}) = int psi'' u_i
///
/// with no initial condition in it. The test functions are psi_q = w(t) e^{i w_q t},
/// w(t) = sin^4(pi t / W), w_q = 2 pi q / W, q = 0 .. Q (Q = band_hz W): their real and imaginary
/// parts give F = 2Q + 1 real rows per DOF. sin^4 is a sum of five exponentials, so every
/// integral int psi_q^(d) x is a combination of five plain Fourier sums X_j = sum_t x e^{i w_j t} dt
/// (j = q-2 .. q+2, X_{-j} = conj X_j): per sample and channel only Q + 3 complex
/// multiply-adds, accumulated in K hop blocks of W/K so that K staggered windows share them.
/// The taper and its first three derivatives vanish at the window ends, so the sums are the
/// integrals to O(dt^4) (window results within 1e-6 of the truth on noise-free tones in the tests).
///
/// Weighting (GLS). The equation error of the rows is linear in the measurement noise: DOF i's
/// rows load channel i through m_i psi'' - c_i psi' + (k_i + k_{i+1}) psi and its neighbours'
/// channels through -k_i psi and -k_{i+1} psi. With white noise of RMS s_c on channel c the
/// covariance of all n F rows is block pentadiagonal,
///   Sigma_ij = sum_c s_c^2 sum_{d,e} l_icd l_jce G_de + delta_ij s_{u,i}^2 G_22,
/// (l_icd the loadings above, G_de = dt^2 sum psi^(d) psi^(e)^T the Gram matrices of the test
/// functions), a known function of the parameters. W = Sigma^-1 over all rows (the rows of
/// neighbouring DOFs share channels; weighting each DOF's rows alone left the 5-DOF springs
/// further from the Cramer-Rao bound in the numpy prototype than the full covariance) is refreshed in
/// the background from the owner's running estimate (set_model()).
///
/// Bias compensation. The regressor noise adds E[N^T W N] to the normal matrix: for every
/// channel, s_c^2 times sums of <W_ij, G_de> over the columns it loads. It is subtracted
/// (errors-in-variables correction). The noise RMS per channel is given (accel_noise,
/// force_noise) or estimated from the fourth difference of the raw signal (variance 70 sigma^2
/// for white noise; a band-limited response at 20 Hz of 1 kHz leaks (2 pi 0.02)^4 of its
/// amplitude into it), exponentially forgotten.
///
/// The parts, each in a header of its own under detail/: the hop-block Fourier sums and the rows
/// (weak_form_sums.hpp, detail::WeakFormSums), the noise estimate (weak_form_noise.hpp,
/// detail::FourthDifferenceNoise), the weights, their background refresh and the bias term
/// (weak_form_weights.hpp, detail::WeakFormWeights). This class runs them per sample and solves
/// each window.
///
/// Window result: the normal equations Phi^T W Phi theta = Phi^T W y of all n F rows (Phi is
/// sparse: a parameter's column has rows in one or two DOFs), corrected, solved (LDLT); the
/// diagonal of the inverse is the window's variance (with GLS weights).
///
/// Real-time contract: the constructor validates and allocates every buffer (sizes depend on
/// window, band and n); update(), restart(), reset() and set_model() are noexcept and allocate
/// nothing. The work of a window (the rows; (3n+1) n products of an F-row block of W with a
/// parameter's column and n^2 of an F x F block of W with a block of the right-hand side; the
/// normal equations row by row; the factorisation; the back-substitutions) is spread over three
/// quarters of a hop (each sample runs the steps that fit in the least budget of multiply-adds,
/// from 2 F^2 up, that finishes the window in time, or one O((3n+1)^3) part),
/// and a weight refresh (Sigma block by block, the Cholesky factor column by column within its
/// band, W column by column a row block at a time, the traces block by block) advances by steps
/// of at most about 9 F^2 multiply-adds, about 6 F^2 per sample, so no sample pays for a whole
/// window or a whole refresh. The first refresh after reset() weights each DOF's rows alone
/// (the diagonal blocks: weighted windows from about 0.1 s after the first estimate); the
/// following ones use the full covariance (about 1.3 s per refresh at n = 5). Arithmetic of
/// the windows is in double whatever Scalar (Sigma spans many decades).
///
/// Storage (F = 2Q+1, J = Q+3 bins, K blocks, R = n F rows): K J 2n complex bins, three R x R
/// matrices (W in force, the next W, the Cholesky factor), 9 F^2 Gram matrices; about 1.8 MB
/// for n = 5 and 6.5 MB for n = 10 at W = 0.5 s, band 50 Hz.

#include "algid/detail/weak_form_noise.hpp"
#include "algid/detail/weak_form_sums.hpp"
#include "algid/detail/weak_form_weights.hpp"
#include "algid/types.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace algid {

/// Configuration of WeakFormWindows.
template <class Scalar>
struct WeakFormConfig {
  Scalar dt = Scalar(1e-3);              ///< sample period [s]
  Boundary boundary = Boundary::kFixed;  ///< right end: wall or free
  Scalar window_s = Scalar(0.5);         ///< window length W [s] (rounded to a multiple of K samples)
  int stagger = 4;                       ///< windows in flight K, started W/K apart
  Scalar band_hz = Scalar(-1);           ///< highest test-function frequency [Hz]; -1: 0.05 / dt
  Scalar accel_noise = Scalar(-1);       ///< RMS of the acceleration noise [m/s^2]; -1: estimated
  Scalar force_noise = Scalar(-1);       ///< RMS of the force noise [N]; -1: estimated
  Scalar noise_horizon_s = Scalar(10);   ///< forgetting time constant of the noise estimate [s]
  bool weighted = true;                  ///< GLS weights from the running estimate (else unweighted)
  bool bias_compensation = true;         ///< subtract the regressor-noise term of the normal matrix
};

/// Why a WeakFormConfig is rejected.
enum class WeakFormConfigError { kNone, kBadSamplePeriod, kBadWindow, kBadStagger, kBadBand, kBadNoise, kBadDofs };

/// Human-readable text of a WeakFormConfigError.
inline const char* to_string(WeakFormConfigError e) noexcept {
  switch (e) {
    case WeakFormConfigError::kNone: return "ok";
    case WeakFormConfigError::kBadSamplePeriod: return "dt must be finite and > 0 [s]";
    case WeakFormConfigError::kBadWindow: return "window_s must be finite and hold at least 32 samples";
    case WeakFormConfigError::kBadStagger: return "stagger must be in [1, MaxStagger]";
    case WeakFormConfigError::kBadBand:
      return "band_hz must be -1 (0.05/dt) or in [2 / window_s, 0.45/dt), with 2 band_hz window_s + 1 <= window "
             "samples / 2";
    case WeakFormConfigError::kBadNoise:
      return "accel_noise and force_noise must be -1 (estimated) or >= 0, noise_horizon_s > 0";
    case WeakFormConfigError::kBadDofs: return "n must be >= 1 (and equal N for a fixed size)";
  }
  return "unknown";
}

/// Weak-form GLS windows of an N-DOF chain (see the file comment).
/// @tparam N number of DOF or Dynamic. @tparam Scalar double or float (inputs, outputs).
/// @tparam MaxStagger most windows in flight.
template <int N, class Scalar = double, int MaxStagger = 8>
class WeakFormWindows {
 public:
  /// Configuration type.
  using Config = WeakFormConfig<Scalar>;
  /// Number of reported parameters m_1..m_N, c_1..c_N, k_1..k_{N+1}.
  static constexpr int kParams = N == Dynamic ? Dynamic : 3 * N + 1;

  /// Check a configuration without side effects. @realtime no allocation, no throw
  static WeakFormConfigError validate(const Config& c, int n = N) noexcept {
    if (n < 1 || (N != Dynamic && n != N)) return WeakFormConfigError::kBadDofs;
    if (!std::isfinite(c.dt) || !(c.dt > Scalar(0))) return WeakFormConfigError::kBadSamplePeriod;
    if (!std::isfinite(c.window_s) || !(c.window_s / c.dt >= Scalar(32)) || c.window_s / c.dt > Scalar(1e7))
      return WeakFormConfigError::kBadWindow;
    if (c.stagger < 1 || c.stagger > MaxStagger) return WeakFormConfigError::kBadStagger;
    const long L = samples_of(c);
    const double band = band_of(c);
    const long Q = static_cast<long>(std::floor(band * static_cast<double>(L) * static_cast<double>(c.dt) + 1e-9));
    if (!std::isfinite(c.band_hz) || (c.band_hz < Scalar(0) && c.band_hz != Scalar(-1)) ||
        !(band * static_cast<double>(c.dt) < 0.45) || Q < 2 || 2 * Q + 1 > L / 2)
      return WeakFormConfigError::kBadBand;
    const auto bad_noise = [](Scalar s) { return !std::isfinite(s) || (s < Scalar(0) && s != Scalar(-1)); };
    if (bad_noise(c.accel_noise) || bad_noise(c.force_noise) || !std::isfinite(c.noise_horizon_s) ||
        !(c.noise_horizon_s > Scalar(0)))
      return WeakFormConfigError::kBadNoise;
    return WeakFormConfigError::kNone;
  }

  /// Configure; throws std::invalid_argument on a bad configuration. Allocates every buffer.
  explicit WeakFormWindows(const Config& config, int n = N)
      : config_(checked(config, n)), n_(n), params_(3 * n + 1), ldlt_(3 * n + 1) {
    L_ = samples_of(config_);
    K_ = config_.stagger;
    H_ = L_ / K_;
    Q_ = static_cast<int>(std::floor(band_of(config_) * static_cast<double>(L_) * dt() + 1e-9));
    F_ = 2 * Q_ + 1;
    R_ = n_ * F_;
    // window steps: rows; P n products of a row block of W with a parameter's column (one or
    // two blocks wide) and n^2 of a block of W with a block of the right-hand side; P rows of
    // the normal equations; the factorisation, the back-substitutions, the misfit. A sample
    // runs the steps that fit in its budget of multiply-adds (at least one): the least budget
    // from 2 F^2 (the largest step) up with which the window is done within three quarters
    // of a hop (the factorisation and the back-substitutions each end their sample).
    products_ = params_ * n_ + n_ * n_;
    window_steps_ = 4 + products_ + params_;
    double total = 0.0;
    for (int step = 0; step < window_steps_; ++step) total += step_cost(step);
    const long due = std::max(3L, 3 * H_ / 4 - 1);
    for (window_budget_ = 2.0 * F_ * F_; latency_samples() > due && window_budget_ < total;) window_budget_ *= 1.05;
    rows_.setZero(F_, 4 * n_);
    phi_.setZero(R_, params_ + 1);
    xw_.setZero(R_, params_ + 1);
    normal_.setZero(params_, params_);
    raw_normal_.setZero(params_, params_);
    rhs_.setZero(params_);
    solution_.setZero(params_);
    work_.setZero(params_);
    inverse_.setZero(params_, params_);
    result_.setZero(params_);
    variance_.setZero(params_);
    sums_.configure(n_, L_, K_, Q_, dt());
    noise_.configure(n_, dt(), static_cast<double>(config_.noise_horizon_s), config_.accel_noise, config_.force_noise);
    weights_.configure(n_, F_, L_, dt(), config_.boundary, config_.weighted);
    reset();
  }

  /// Forget everything: windows, weights (back to unweighted), noise estimate, model.
  /// @realtime no allocation, no throw
  void reset() noexcept {
    restart();
    weights_.reset();
    noise_.reset();
    results_ = 0;
    misfit_ = std::numeric_limits<double>::quiet_NaN();
    result_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
    variance_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
  }

  /// Drop the windows in flight (after a bad sample); weights and noise estimate are kept.
  /// @realtime no allocation, no throw
  void restart() noexcept {
    noise_.restart();  // no differences across the gap
    sums_.restart();
    pending_ = false;
    step_ = 0;
  }

  /// Running parameters (m, c, k packed, 3n+1) that the GLS weights are computed from; NaN or
  /// non-positive masses keep the current weights. @realtime no allocation, no throw
  void set_model(const Scalar* theta) noexcept { weights_.set_model(theta); }

  /// Consume one sample of the accelerations [m/s^2] and forces [N] (finite: the owner checks).
  /// Returns true when a window result was completed by this call (see result()).
  /// @realtime no allocation, no throw; O((Q + 3) 2n) plus one step of at most about 3 F^2 flops
  bool update(const Scalar* accel, const Scalar* force) noexcept {
    const int n = n_;
    for (int i = 0; i < n; ++i) {
      noise_.observe(i, static_cast<double>(accel[i]));
      noise_.observe(n + i, static_cast<double>(force[i]));
    }
    if (sums_.add(accel, force)) {
      pending_ = true;
      step_ = 0;
    }
    bool done = false;
    for (double spent = 0.0; pending_;) {
      const int step = step_;
      const double cost = step_cost(step);
      if (spent > 0.0 && spent + cost > window_budget_) break;
      spent += cost;
      done = window_step() || done;
      if (heavy_step(step)) break;  // an O(P^3) step ran: the rest waits for the next sample
    }
    weights_.refresh(noise_, pending_);
    return done;
  }

  /// The latest window result (3n+1, NaN where not identified or the window was singular).
  const Vector<Scalar, kParams>& result() const noexcept { return result_; }
  /// Its variance per parameter (diagonal of the inverse corrected normal matrix; NaN until
  /// every DOF's rows were GLS-weighted when the window started) [parameter units^2].
  const Vector<Scalar, kParams>& variance() const noexcept { return variance_; }
  /// The latest window's corrected normal equations N theta = b (3n+1; parameters that no
  /// equation holds are pinned: unit diagonal, zero right-hand side), in double.
  const Eigen::MatrixXd& normal() const noexcept { return normal_; }
  /// Right-hand side b of normal().
  const Eigen::VectorXd& rhs() const noexcept { return rhs_; }
  /// True if the latest window's rows were all GLS-weighted (normal() is then an information
  /// matrix: windows can be summed).
  bool result_weighted() const noexcept { return window_weighted_; }
  /// True if those weights were the full covariance's (the first refresh weights each DOF's rows
  /// alone): normal() is then the window's information matrix, and its inverse the variance.
  bool result_fully_weighted() const noexcept { return window_full_; }
  /// Weighted residual of the latest window per degree of freedom, r^T W r / (n F - 3n - 1)
  /// with r = y - Phi theta at the window's own solution: about 1 when the chain and the noise
  /// estimate describe the window; NaN for an unweighted or failed window.
  double misfit() const noexcept { return misfit_; }
  /// Window results since reset().
  long results() const noexcept { return results_; }
  /// True once every DOF's rows are weighted by a covariance from the running estimate.
  bool weighted() const noexcept { return weights_.weighted(); }
  /// Estimated (or given) noise RMS of channel c: accelerations 0..n-1, forces n..2n-1.
  Scalar noise_rms(int c) const noexcept { return static_cast<Scalar>(std::sqrt(noise_.variance(c))); }
  /// Window length L [samples].
  long window_samples() const noexcept { return L_; }
  /// Samples between two window results.
  long hop_samples() const noexcept { return H_; }
  /// Samples from the end of a window to its result.
  long latency_samples() const noexcept {
    long sample = 0;
    double spent = 0.0;
    for (int step = 0; step < window_steps_; ++step) {
      if (spent > 0.0 && spent + step_cost(step) > window_budget_) ++sample, spent = 0.0;
      spent += step_cost(step);
      if (heavy_step(step)) spent = window_budget_ + 1.0;  // ends the sample
    }
    return sample;
  }
  /// Highest test-function frequency [Hz] a configuration asks for (`band_hz`, or 0.05 / dt for -1).
  static double band_of(const Config& c) noexcept {
    return c.band_hz < Scalar(0) ? 0.05 / static_cast<double>(c.dt) : static_cast<double>(c.band_hz);
  }
  /// Highest harmonic Q of the test functions (F = 2Q+1 rows per DOF).
  int harmonics() const noexcept { return Q_; }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 private:
  using MatD = Eigen::MatrixXd;
  using VecD = Eigen::VectorXd;

  double dt() const noexcept { return static_cast<double>(config_.dt); }

  static long samples_of(const Config& c) noexcept {
    const long raw = std::lround(static_cast<double>(c.window_s) / static_cast<double>(c.dt));
    const long k = std::max(1, c.stagger);
    return std::max(k, raw / k * k);
  }
  static const Config& checked(const Config& c, int n) {
    const WeakFormConfigError e = validate(c, n);
    if (e != WeakFormConfigError::kNone) detail::config_error(to_string(e));
    return c;
  }

  // True if DOF i has a spring to its right in the model (a neighbour or the right wall).
  bool right(int i) const noexcept { return detail::right_spring(i, n_, config_.boundary); }

  // Row blocks [first, last] where column p of phi_ (a parameter, or p = params_: the
  // right-hand side) has rows; first > last if none.
  void span(int p, int& first, int& last) const noexcept {
    const int n = n_;
    if (p < 2 * n) {
      first = last = p % n;
    } else if (p < params_) {  // spring j = p - 2n joins DOF j-1 and j
      const int j = p - 2 * n;
      first = j > 0 && right(j - 1) ? j - 1 : j;
      last = j < n ? j : n - 1;
      if (j == n && !right(n - 1)) first = last + 1;
    } else {
      first = 0;
      last = n - 1;
    }
  }

  // The window's regressors: phi_ block i holds DOF i's equation (eq. 1 in weak form), its
  // columns the parameters m, c, k and the right-hand side int psi'' u.
  void fill_phi() noexcept {
    const int n = n_, F = F_;
    phi_.setZero();
    for (int i = 0; i < n; ++i) {
      auto block = phi_.middleRows(i * F, F);
      block.col(i) = rows_.col(2 * n + i);
      block.col(n + i) = -rows_.col(n + i);
      block.col(2 * n + i) = rows_.col(i);  // k_i (for n = 1 with walls: k_1 + k_2)
      if (i > 0) block.col(2 * n + i) -= rows_.col(i - 1);
      if (right(i)) {
        block.col(2 * n + i + 1) = rows_.col(i);
        if (i + 1 < n) block.col(2 * n + i + 1) -= rows_.col(i + 1);
      }
      block.col(params_) = rows_.col(3 * n + i);
    }
  }

  // The factorisation and the back-substitutions: O(P^3), each ends its sample.
  bool heavy_step(int step) const noexcept { return step == window_steps_ - 3 || step == window_steps_ - 2; }

  // Multiply-adds of window step `step` (at least 1; the O(P^3) steps end their sample instead).
  double step_cost(int step) const noexcept {
    const int F = F_, n = n_, Pn = params_ * n_;
    int first = 0, last = -1;
    double cost = 0.0;
    if (step == 0) {
      cost = 5.0 * F * 4 * n;  // rows: five bins per row and channel
    } else if (step <= Pn) {
      span((step - 1) / n, first, last);
      cost = static_cast<double>(F) * F * (last - first + 1);
    } else if (step <= products_) {
      cost = static_cast<double>(F) * F;
    } else if (step <= products_ + params_) {
      span(step - 1 - products_, first, last);
      cost = static_cast<double>(F) * (last - first + 1) * (params_ + 1);
    }
    return std::max(1.0, cost);
  }

  // One step of the pending window: rows; a product of a row block of the weights with a
  // parameter's column of phi_ (at most 2 F^2 multiply-adds) or of an F x F block of the
  // weights with a block of the right-hand side column (which spans every DOF); a row of the
  // normal equations; the bias and the factorisation; the solution and the inverse; the
  // misfit. Each O(P^3) part has a step of its own, so no sample carries more than one of them.
  bool window_step() noexcept {
    const int F = F_, n = n_, P = params_, Pn = params_ * n;
    if (step_ == 0) {
      window_weighted_ = weights_.weighted();
      window_full_ = weights_.weighted() && weights_.full();
      sums_.rows(rows_);
      fill_phi();
    } else if (step_ <= Pn) {
      const int p = (step_ - 1) / n, r = (step_ - 1) % n;
      int first, last;
      span(p, first, last);
      auto out = xw_.col(p).segment(r * F, F);
      if (first > last) {
        out.setZero();
      } else if (window_weighted_) {
        const int w = (last - first + 1) * F;
        out.noalias() = weights_.matrix().block(r * F, first * F, F, w) * phi_.col(p).segment(first * F, w);
      } else {
        out = phi_.col(p).segment(r * F, F);
      }
    } else if (step_ <= products_) {
      const int r = (step_ - 1 - Pn) / n, c = (step_ - 1 - Pn) % n;
      auto out = xw_.col(P).segment(r * F, F);
      if (!window_weighted_) {
        if (c == 0) out = phi_.col(P).segment(r * F, F);
      } else if (c == 0) {
        out.noalias() = weights_.matrix().block(r * F, 0, F, F) * phi_.col(P).segment(0, F);
      } else {
        out.noalias() += weights_.matrix().block(r * F, c * F, F, F) * phi_.col(P).segment(c * F, F);
      }
    } else if (step_ <= products_ + params_) {
      const int p = step_ - 1 - products_;
      int first, last;
      span(p, first, last);
      if (first > last) {
        normal_.row(p).setZero();
        rhs_(p) = 0.0;
      } else {
        const int w = (last - first + 1) * F;
        normal_.row(p).noalias() = phi_.col(p).segment(first * F, w).transpose() * xw_.block(first * F, 0, w, params_);
        rhs_(p) = phi_.col(p).segment(first * F, w).dot(xw_.col(params_).segment(first * F, w));
      }
    } else if (step_ == products_ + params_ + 1) {
      raw_normal_ = normal_;
      if (config_.bias_compensation) weights_.subtract_bias(normal_, noise_, window_weighted_);
      factor();
    } else if (step_ == products_ + params_ + 2) {
      solve();
    } else {
      measure_misfit();
      pending_ = false;
      ++results_;
      return true;
    }
    ++step_;
    return false;
  }

  // Parameters absent from every equation (k_{n+1} with a free end or n = 1) are pinned; the
  // corrected normal matrix is factored.
  void factor() noexcept {
    if (free_last()) {
      normal_.row(params_ - 1).setZero();
      normal_.col(params_ - 1).setZero();
      normal_(params_ - 1, params_ - 1) = 1.0;
      rhs_(params_ - 1) = 0.0;
    }
    ldlt_.compute(normal_);
  }

  bool free_last() const noexcept { return config_.boundary == Boundary::kFree || n_ == 1; }

  // The window's result and variances from the factorisation of factor().
  void solve() noexcept {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    bool ok = ldlt_.info() == Eigen::Success && ldlt_.isPositive();
    if (ok) {
      inverse_.setIdentity();
      ldlt_.solveInPlace(inverse_);
      VecD& x = solution_;
      x = rhs_;
      ldlt_.solveInPlace(x);
      for (int j = 0; j < params_; ++j) {
        ok = ok && std::isfinite(x(j));
        result_(j) = static_cast<Scalar>(x(j));
        // the inverse normal matrix is the covariance only with GLS weights
        variance_(j) = window_weighted_ ? static_cast<Scalar>(inverse_(j, j)) : static_cast<Scalar>(nan);
      }
    }
    if (!ok) {
      result_.setConstant(static_cast<Scalar>(nan));
      variance_.setConstant(static_cast<Scalar>(nan));
    }
    if (free_last()) {
      result_(params_ - 1) = config_.boundary == Boundary::kFree ? Scalar(0) : static_cast<Scalar>(nan);
      variance_(params_ - 1) = Scalar(0);
    }
  }

  // r^T W r = y^T W y - 2 theta^T Phi^T W y + theta^T Phi^T W Phi theta, with the normal
  // matrix before the bias correction (the residual of the rows as measured).
  void measure_misfit() noexcept {
    misfit_ = std::numeric_limits<double>::quiet_NaN();
    if (!window_weighted_ || !result_.allFinite()) return;
    const double yy = phi_.col(params_).dot(xw_.col(params_));
    const VecD& x = solution_;
    work_.noalias() = raw_normal_ * x;
    const double r2 = yy - 2.0 * x.dot(rhs_) + x.dot(work_);
    misfit_ = std::max(r2, 0.0) / static_cast<double>(std::max(1, R_ - params_));
  }

  Config config_;
  int n_;
  int params_;
  Eigen::LDLT<MatD> ldlt_;
  long L_ = 0, H_ = 0;
  int K_ = 1, Q_ = 0, F_ = 0, R_ = 0, window_steps_ = 1, products_ = 0;
  double window_budget_ = 1.0;  // multiply-adds of window steps per sample
  MatD rows_, phi_, xw_, normal_, raw_normal_, inverse_;
  detail::WeakFormSums sums_;
  detail::FourthDifferenceNoise<Scalar, N == Dynamic ? Dynamic : 2 * N> noise_;
  detail::WeakFormWeights weights_;
  VecD rhs_, solution_, work_;
  bool pending_ = false;
  int step_ = 0;
  bool window_weighted_ = false, window_full_ = false;  // the latest window's rows: weighted; by the full covariance
  long results_ = 0;
  double misfit_ = std::numeric_limits<double>::quiet_NaN();
  Vector<Scalar, kParams> result_, variance_;
};

}  // namespace algid
