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
/// Weighting (GLS). The equation error of the rows of DOF i is linear in the measurement
/// noise; with white noise of RMS sigma_c on channel c its covariance is
///   Sigma_i = s_i^2 [m^2 G22 + c^2 G11 + kk^2 G00 - m c S12 + m kk S02 - c kk S01]
///             + (s_{i-1}^2 k_i^2 + s_{i+1}^2 k_{i+1}^2) G00 + s_{u,i}^2 G22
/// (kk = k_i + k_{i+1}, Gde = dt^2 sum psi^(d) psi^(e)^T the Gram matrices of the test functions,
/// Sde = Gde + Ged), a known function of the parameters. W_i = Sigma_i^-1 is refreshed in the
/// background from the owner's running estimate (set_model()); the rows of one DOF are weighted
/// by it, the cross-DOF correlation is left out (measured: no loss on the benchmark).
///
/// Bias compensation. The regressor noise adds E[N^T W N] to the normal matrix; it is
/// s^2-weighted traces <W, Gde> (d, e = 0..2) and is subtracted (errors-in-variables correction).
/// The noise RMS per channel is given (accel_noise, force_noise) or estimated from the fourth
/// difference of the raw signal (variance 70 sigma^2 for white noise; a band-limited response
/// at 20 Hz of 1 kHz leaks (2 pi 0.02)^4 of its amplitude into it), exponentially forgotten.
///
/// Window result: the per-DOF normal equations, corrected, summed into one (3n+1)^2 system
/// (interior springs appear in two DOFs) and solved (LDLT); the diagonal of its inverse is the
/// window's variance (with GLS weights).
///
/// Real-time contract: the constructor validates and allocates every buffer (sizes depend on
/// window and band); update(), restart(), reset() and set_model() are noexcept and allocate
/// nothing. The work of a window (rows, one DOF per step, the solve) and of a weight refresh
/// (Sigma, Cholesky by columns, W by columns) is cut into steps of at most about 3 F^2 flops,
/// one step per sample (more when n is large), so no sample pays for a whole window.
/// Arithmetic of the windows is in double whatever Scalar (Sigma spans many decades).
///
/// Storage (F = 2Q+1, J = Q+3 bins, K blocks): K (J) 2n complex bins, n F^2 weights, 6 F^2 Gram
/// matrices, about 0.7 MB for n = 5, W = 0.5 s, band 50 Hz.

#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <complex>
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
    J_ = Q_ + 3;
    F_ = 2 * Q_ + 1;
    // window steps (rows, n DOFs, solve) within half a hop
    const long half = std::max(1L, H_ / 2);
    steps_ = static_cast<int>(std::max(1L, (static_cast<long>(n_) + 2 + half - 1) / half));
    const int C = 2 * n_;
    z_.resize(J_);
    bins_.setZero(J_, C * K_);
    seg_.setZero(J_, C);
    rows_.setZero(F_, 3 * n_ + n_);
    weights_.resize(n_);
    traces_.resize(n_);
    for (int i = 0; i < n_; ++i) weights_[i].setZero(F_, F_);
    sigma_.setZero(F_, F_);
    chol_.setZero(F_, F_);
    wnext_.setZero(F_, F_);
    phi_.setZero(F_, 5);
    wphi_.setZero(F_, 5);
    normal_.setZero(params_, params_);
    rhs_.setZero(params_);
    solution_.setZero(params_);
    inverse_.setZero(params_, params_);
    model_.setConstant(params_, std::numeric_limits<double>::quiet_NaN());
    noise_.resize(C);
    history_.resize(C);
    result_.setZero(params_);
    variance_.setZero(params_);
    gram();
    reset();
  }

  /// Forget everything: windows, weights (back to unweighted), noise estimate, model.
  /// @realtime no allocation, no throw
  void reset() noexcept {
    restart();
    for (int i = 0; i < n_; ++i) {
      weights_[i].setIdentity();
      traces_[i] = identity_traces_;
    }
    weighted_ = false;
    for (int c = 0; c < 2 * n_; ++c) {
      noise_[c] = Noise{};
      history_[c] = History{};
    }
    model_.setConstant(std::numeric_limits<double>::quiet_NaN());
    refresh_dof_ = 0;
    refresh_stage_ = 0;
    results_ = 0;
    result_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
    variance_.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
  }

  /// Drop the windows in flight (after a bad sample); weights and noise estimate are kept.
  /// @realtime no allocation, no throw
  void restart() noexcept {
    bins_.setZero();
    phase_ = 0;
    in_hop_ = 0;
    hops_ = 0;
    pending_ = false;
    step_ = 0;
  }

  /// Running parameters (m, c, k packed, 3n+1) that the GLS weights are computed from; NaN or
  /// non-positive masses keep the current weights. @realtime no allocation, no throw
  void set_model(const Scalar* theta) noexcept {
    for (int j = 0; j < params_; ++j) model_(j) = static_cast<double>(theta[j]);
  }

  /// Consume one sample of the accelerations [m/s^2] and forces [N] (finite: the owner checks).
  /// Returns true when a window result was completed by this call (see result()).
  /// @realtime no allocation, no throw; O((Q + 3) 2n) plus one step of at most about 3 F^2 flops
  bool update(const Scalar* accel, const Scalar* force) noexcept {
    const int n = n_;
    for (int i = 0; i < n; ++i) {
      observe(i, static_cast<double>(accel[i]));
      observe(n + i, static_cast<double>(force[i]));
    }
    // Fourier sums of this hop block: phasors e^{i 2 pi j phase / L}, j = 0 .. J-1.
    const double angle = kTwoPi * static_cast<double>(phase_) / static_cast<double>(L_);
    const Complex z1(std::cos(angle), std::sin(angle));
    z_(0) = Complex(dt(), 0.0);
    for (int j = 1; j < J_; ++j) z_(j) = z_(j - 1) * z1;
    const int block = static_cast<int>(hops_ % K_);
    for (int c = 0; c < 2 * n; ++c) {
      const double x = c < n ? static_cast<double>(accel[c]) : static_cast<double>(force[c - n]);
      bins_.col(block * 2 * n + c) += x * z_;
    }
    if (++phase_ == L_) phase_ = 0;
    bool done = false;
    if (++in_hop_ == H_) {
      in_hop_ = 0;
      ++hops_;
      if (hops_ >= K_) start_window();
      bins_.middleCols(static_cast<int>(hops_ % K_) * 2 * n, 2 * n).setZero();  // the oldest block restarts
    }
    for (int s = 0; s < steps_; ++s) {
      if (pending_) {
        done = window_step() || done;
      } else {
        refresh_step();
      }
    }
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
  /// Window results since reset().
  long results() const noexcept { return results_; }
  /// True once every DOF's rows are weighted by a covariance from the running estimate.
  bool weighted() const noexcept { return weighted_; }
  /// Estimated (or given) noise RMS of channel c: accelerations 0..n-1, forces n..2n-1.
  Scalar noise_rms(int c) const noexcept { return static_cast<Scalar>(std::sqrt(noise_variance(c))); }
  /// Window length L [samples].
  long window_samples() const noexcept { return L_; }
  /// Samples between two window results.
  long hop_samples() const noexcept { return H_; }
  /// Highest harmonic Q of the test functions (F = 2Q+1 rows per DOF).
  int harmonics() const noexcept { return Q_; }
  /// The configuration in force.
  const Config& config() const noexcept { return config_; }

 private:
  using Complex = std::complex<double>;
  using MatD = Eigen::MatrixXd;
  using VecD = Eigen::VectorXd;
  using MatC = Eigen::Matrix<Complex, Eigen::Dynamic, Eigen::Dynamic>;
  using VecC = Eigen::Matrix<Complex, Eigen::Dynamic, 1>;
  static constexpr double kTwoPi = 6.283185307179586476925;
  // sin^4(x) = 3/8 - cos(2x)/2 + cos(4x)/8: coefficients of e^{i 2 pi k t / W}, k = -2..2.
  static constexpr double kTaper[5] = {1.0 / 16, -1.0 / 4, 3.0 / 8, -1.0 / 4, 1.0 / 16};

  struct Noise {
    double sum = 0.0;  // forgotten sum of squared fourth differences
    double weight = 0.0;  // forgotten count
  };
  struct History {
    double x[4] = {0.0, 0.0, 0.0, 0.0};
    int count = 0;
  };
  struct Traces {  // <W, Gde> for (d, e) = 00, 11, 22, 01, 02, 12
    double t[6] = {0, 0, 0, 0, 0, 0};
  };

  double dt() const noexcept { return static_cast<double>(config_.dt); }

  static long samples_of(const Config& c) noexcept {
    const long raw = std::lround(static_cast<double>(c.window_s) / static_cast<double>(c.dt));
    const long k = std::max(1, c.stagger);
    return std::max(k, raw / k * k);
  }
  static double band_of(const Config& c) noexcept {
    return c.band_hz < Scalar(0) ? 0.05 / static_cast<double>(c.dt) : static_cast<double>(c.band_hz);
  }
  static const Config& checked(const Config& c, int n) {
    const WeakFormConfigError e = validate(c, n);
    if (e != WeakFormConfigError::kNone) detail::config_error(to_string(e));
    return c;
  }

  // Gram matrices of the test functions and their derivatives (configuration phase).
  void gram() {
    const double W = static_cast<double>(L_) * dt();
    MatD psi[3];
    for (auto& p : psi) p.setZero(F_, L_);
    for (long l = 0; l < L_; ++l) {
      const double t = static_cast<double>(l) * dt();
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
    const double d2 = dt() * dt();
    const int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    for (int p = 0; p < 6; ++p) {
      gram_[p] = d2 * psi[pairs[p][0]] * psi[pairs[p][1]].transpose();
      if (pairs[p][0] != pairs[p][1]) gram_[p] += gram_[p].transpose().eval();  // S01, S02, S12
      identity_traces_.t[p] = gram_[p].trace() / (pairs[p][0] != pairs[p][1] ? 2.0 : 1.0);
    }
  }

  void observe(int c, double x) noexcept {
    History& h = history_[c];
    if (h.count == 4) {
      const double d4 = x - 4 * h.x[3] + 6 * h.x[2] - 4 * h.x[1] + h.x[0];
      const double keep = 1.0 - dt() / static_cast<double>(config_.noise_horizon_s);
      Noise& s = noise_[c];
      s.sum = keep * s.sum + d4 * d4;
      s.weight = keep * s.weight + 1.0;
    }
    h.x[0] = h.x[1];
    h.x[1] = h.x[2];
    h.x[2] = h.x[3];
    h.x[3] = x;
    h.count = std::min(h.count + 1, 4);
  }

  double noise_variance(int c) const noexcept {
    const Scalar given = c < n_ ? config_.accel_noise : config_.force_noise;
    if (given >= Scalar(0)) return static_cast<double>(given) * static_cast<double>(given);
    const Noise& s = noise_[c];
    return s.weight > 0.0 ? s.sum / (70.0 * s.weight) : 0.0;
  }

  // The K newest hop blocks form a window: sum them, shift the phasors to its start.
  void start_window() noexcept {
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
    pending_ = true;
    step_ = 0;
  }

  // Bin j of channel c with X_{-j} = conj(X_j).
  Complex bin(int j, int c) const noexcept { return j >= 0 ? seg_(j, c) : std::conj(seg_(-j, c)); }

  // Rows of the window: rows_ columns 0..n-1: int psi a (d = 0), n..2n-1: d = 1, 2n..3n-1:
  // d = 2, 3n..4n-1: int psi'' u.
  void build_rows() noexcept {
    const double W = static_cast<double>(L_) * dt();
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
          rows_(2 * q == 0 ? 0 : 2 * q - 1, col) = v.real();
          if (q > 0) rows_(2 * q, col) = v.imag();
        }
      }
    }
  }

  // Columns of DOF i's equation: parameter index, and the rows_ columns combined.
  int columns(int i, int* param) const noexcept {
    int count = 0;
    param[count++] = i;
    param[count++] = n_ + i;
    param[count++] = 2 * n_ + i;  // k_i (left spring; for n = 1 with a wall it holds k_1 + k_2)
    const bool right = n_ > 1 && (i + 1 < n_ || config_.boundary == Boundary::kFixed);
    if (right) param[count++] = 2 * n_ + i + 1;
    return count;
  }

  // One DOF's corrected normal equations into normal_ / rhs_.
  void add_dof(int i) noexcept {
    const int n = n_;
    int param[4];
    const int cols = columns(i, param);
    phi_.col(0) = rows_.col(2 * n + i);
    phi_.col(1) = -rows_.col(n + i);
    phi_.col(2) = rows_.col(i);
    if (i > 0) phi_.col(2) -= rows_.col(i - 1);
    if (cols == 4) {
      phi_.col(3) = rows_.col(i);
      if (i + 1 < n) phi_.col(3) -= rows_.col(i + 1);
    }
    phi_.col(4) = rows_.col(3 * n + i);
    const MatD& W = weights_[i];
    wphi_.noalias() = W * phi_;
    // Bias: noise loadings of the columns on the own channel (derivative order, sign).
    const int order[4] = {2, 1, 0, 0};
    const double sign[4] = {1.0, -1.0, 1.0, 1.0};
    const Traces& T = traces_[i];
    const double own = config_.bias_compensation ? noise_variance(i) : 0.0;
    const double left = config_.bias_compensation && i > 0 ? noise_variance(i - 1) : 0.0;
    const double right = config_.bias_compensation && i + 1 < n ? noise_variance(i + 1) : 0.0;
    for (int a = 0; a < cols; ++a) {
      for (int b = 0; b < cols; ++b) {
        double v = phi_.col(a).dot(wphi_.col(b));
        v -= own * sign[a] * sign[b] * trace(T, order[a], order[b]);
        if (a == 2 && b == 2) v -= left * T.t[0];
        if (a == 3 && b == 3) v -= right * T.t[0];
        normal_(param[a], param[b]) += v;
      }
      rhs_(param[a]) += phi_.col(a).dot(wphi_.col(4));
    }
  }

  static double trace(const Traces& T, int d, int e) noexcept {
    if (d > e) std::swap(d, e);
    if (d == e) return T.t[d];                 // 00, 11, 22
    return T.t[d == 0 ? (e == 1 ? 3 : 4) : 5];  // 01, 02, 12
  }

  // One step of the pending window: rows, then one DOF per step, then the solve.
  bool window_step() noexcept {
    if (step_ == 0) {
      window_weighted_ = weighted_;
      build_rows();
      normal_.setZero();
      rhs_.setZero();
    } else if (step_ <= n_) {
      add_dof(step_ - 1);
    } else {
      solve();
      pending_ = false;
      ++results_;
      return true;
    }
    ++step_;
    return false;
  }

  void solve() noexcept {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const bool free_last = config_.boundary == Boundary::kFree || n_ == 1;
    // Parameters absent from every equation (k_{n+1} with a free end or n = 1): pin them.
    if (free_last) {
      normal_(params_ - 1, params_ - 1) = 1.0;
      rhs_(params_ - 1) = 0.0;
    }
    ldlt_.compute(normal_);
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
    if (free_last) {
      result_(params_ - 1) = config_.boundary == Boundary::kFree ? Scalar(0) : static_cast<Scalar>(nan);
      variance_(params_ - 1) = Scalar(0);
    }
  }

  // Background refresh of the weights of one DOF at a time: stage 0 builds Sigma from the
  // model, stages 1..F factor it column by column (left-looking Cholesky), stages F+1..2F
  // form W = Sigma^-1 column by column and the traces <W, Gde>; then W is swapped in.
  void refresh_step() noexcept {
    if (!config_.weighted) return;
    const int i = refresh_dof_;
    const int F = F_;
    if (refresh_stage_ == 0) {
      if (!build_sigma(i)) return;  // no usable model yet
      for (double& t : next_traces_.t) t = 0.0;
      refresh_stage_ = 1;
      return;
    }
    const int per_step = std::max(1, F / 8);
    if (refresh_stage_ <= F) {
      for (int s = 0; s < per_step && refresh_stage_ <= F; ++s) {
        const int j = refresh_stage_ - 1;
        double d = sigma_(j, j) - chol_.row(j).head(j).squaredNorm();
        if (!(d > 0.0) || !std::isfinite(d)) {  // not positive definite: keep the old weights
          refresh_stage_ = 0;
          refresh_dof_ = (i + 1) % n_;
          return;
        }
        d = std::sqrt(d);
        chol_(j, j) = d;
        const int below = F - j - 1;
        if (below > 0) {
          auto col = chol_.col(j).tail(below);
          col = sigma_.col(j).tail(below);
          col.noalias() -= chol_.bottomLeftCorner(below, j) * chol_.row(j).head(j).transpose();
          col /= d;
        }
        ++refresh_stage_;
      }
      return;
    }
    for (int s = 0; s < 2 && refresh_stage_ <= 2 * F; ++s) {
      const int j = refresh_stage_ - F - 1;
      auto w = wnext_.col(j);
      w.setZero();
      w(j) = 1.0;
      chol_.template triangularView<Eigen::Lower>().solveInPlace(w);
      chol_.template triangularView<Eigen::Lower>().transpose().solveInPlace(w);
      for (int p = 0; p < 6; ++p) {
        const double half = p >= 3 ? 0.5 : 1.0;  // S = G + G^T: <W, G> = <W, S> / 2
        next_traces_.t[p] += half * w.dot(gram_[p].col(j));
      }
      ++refresh_stage_;
    }
    if (refresh_stage_ > 2 * F) {
      weights_[i] = wnext_;
      traces_[i] = next_traces_;
      weighted_dofs_ = std::min(weighted_dofs_ + 1, n_);
      if (i == n_ - 1) weighted_ = true;
      refresh_stage_ = 0;
      refresh_dof_ = (i + 1) % n_;
    }
  }

  // Sigma of DOF i from the model; false if the model is not usable.
  bool build_sigma(int i) noexcept {
    const int n = n_;
    const double m = model_(i), c = model_(n + i), kl = model_(2 * n + i);
    const bool right = n > 1 && (i + 1 < n || config_.boundary == Boundary::kFixed);
    const double kr = right ? model_(2 * n + i + 1) : 0.0;
    if (!(m > 0.0) || !std::isfinite(c) || !std::isfinite(kl) || !std::isfinite(kr)) return false;
    const double kk = kl + kr;
    const double own = noise_variance(i);
    const double left = i > 0 ? noise_variance(i - 1) * kl * kl : 0.0;
    const double rgt = i + 1 < n ? noise_variance(i + 1) * kr * kr : 0.0;
    const double fu = noise_variance(n + i);
    if (!(own > 0.0)) return false;  // noise-free: the weights do not matter
    // gram_: 0 G00, 1 G11, 2 G22, 3 S01, 4 S02, 5 S12
    sigma_.noalias() = (own * m * m + fu) * gram_[2];
    sigma_.noalias() += (own * c * c) * gram_[1];
    sigma_.noalias() += (own * kk * kk + left + rgt) * gram_[0];
    sigma_.noalias() -= (own * m * c) * gram_[5];
    sigma_.noalias() += (own * m * kk) * gram_[4];
    sigma_.noalias() -= (own * c * kk) * gram_[3];
    chol_.setZero();
    return true;
  }

  Config config_;
  int n_;
  int params_;
  Eigen::LDLT<MatD> ldlt_;
  long L_ = 0, H_ = 0;
  int K_ = 1, Q_ = 0, J_ = 0, F_ = 0, steps_ = 1;
  long phase_ = 0, in_hop_ = 0, hops_ = 0;
  VecC z_;
  MatC bins_, seg_;
  MatD rows_, phi_, wphi_, sigma_, chol_, wnext_, normal_, inverse_;
  MatD gram_[6];
  Traces identity_traces_{}, next_traces_{};
  detail::Storage<MatD, N> weights_{};
  detail::Storage<Traces, N> traces_{};
  detail::Storage<Noise, N == Dynamic ? Dynamic : 2 * N> noise_{};
  detail::Storage<History, N == Dynamic ? Dynamic : 2 * N> history_{};
  VecD rhs_, solution_, model_;
  bool pending_ = false;
  int step_ = 0;
  int refresh_dof_ = 0, refresh_stage_ = 0, weighted_dofs_ = 0;
  bool weighted_ = false, window_weighted_ = false;
  long results_ = 0;
  Vector<Scalar, kParams> result_, variance_;
};

}  // namespace algid
