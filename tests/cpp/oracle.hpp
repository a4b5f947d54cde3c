#pragma once
// Test oracle: a plain, scalar, deliberately slow implementation of the paper's estimator for one
// window from t0, written independently of ChainEstimator's lane layout. For each DOF:
//   - one integrator chain per signal (every acceleration, every force) advanced with the
//     weights of algid::InterpolatoryRule as plain loops over doubles (the whole record since t0
//     is kept, the stencil read from it);
//   - the eq. 5 system of the DOF assembled in an Eigen dynamic matrix from the time-scaled
//     moments I^r(Delta^p f) / tau^(r+p) (algid::scaled_moment) of the eq. 4 operators:
//       mass column and right-hand side  I^q(Delta^2 f - 4 I(Delta f) + 2 I^2 f),
//       damping column                   I^(q+1)(Delta^2 f) - 2 I^(q+2)(Delta f),
//       spring columns                   I^(q+2)(Delta^2 (y_i - y_neighbour)),
//     4x4 (3x3 for the last DOF at a free end, and for n = 1 with walls: k_1 + k_2);
//   - solved with Eigen's FullPivLU (not Cramer), theta = [phi_0, phi_1 / tau, phi_2 / tau^2,
//     phi_3 / tau^2];
//   - the validity rule: samples since t0 >= min_samples, det finite and non-zero, Hadamard ratio
//     of the doubly normalised matrix (columns to unit norm, then rows), |det| of it through LU,
//     >= min_hadamard;
//   - eq. 7 as trapezoidal double integrals from t0 of the *physical* |det A| = |det S| tau^q
//     (q = 19 for 4x4, 12 for 3x3) and of |det A| theta_j (sgn(det) det theta), no rescaling;
//   - the springs fused as ChainEstimator documents (mean of both estimates of an interior
//     spring where both DOF are valid, else the valid one; 0 at a free end; k_1 + k_2 and NaN
//     for n = 1 with walls).
#include <algid/chain_config.hpp>
#include <algid/integrator_chain.hpp>
#include <algid/quadrature.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <vector>

namespace algid_test {

/// I^1 .. I^Orders of one sampled signal from t0, by the interpolatory rule, plain doubles.
template <int P, int Orders, class Real = double>
class ScalarChain {
 public:
  using Rule = algid::InterpolatoryRule<P, Orders, Real>;
  void reset() {
    f_.clear();
    for (Real& s : state_) s = Real(0);
  }
  /// Consume a sample; true when the integrals have advanced to a new interval end.
  bool push(Real x, const Rule& rule) {
    f_.push_back(x);
    const long count = static_cast<long>(f_.size());
    if (count < P) return false;
    const long j = count - P;  // interval [t_j, t_{j+1}]
    const long start = Rule::stencil_start(j);
    const int off = static_cast<int>(j - start);
    Real step[Orders];
    for (int r = 0; r < Orders; ++r) {
      Real acc = 0;
      for (int m = 0; m < P; ++m) acc += rule.weights(off)(r, m) * f_[static_cast<std::size_t>(start + m)];
      for (int q = 0; q < r; ++q) acc += rule.carry()(r, q) * state_[q];
      step[r] = acc;
    }
    for (int r = 0; r < Orders; ++r) state_[r] += step[r];
    end_ = j + 1;
    return true;
  }
  /// I^r at the current interval end (r = 0: the sample there).
  Real integral(int r) const { return r == 0 ? f_[static_cast<std::size_t>(end_)] : state_[r - 1]; }
  long count() const { return static_cast<long>(f_.size()); }

 private:
  std::vector<Real> f_;
  Real state_[Orders] = {};
  long end_ = 0;
};

/// The estimator of one window, per DOF, as the paper writes it (see the file comment), in
/// arithmetic Real (double; long double to see which side of a difference rounding is on).
template <int P = 8, class Real = double>
class Oracle {
 public:
  static constexpr int kOrders = 7;
  using Rule = algid::InterpolatoryRule<P, kOrders, Real>;
  using MatrixR = Eigen::Matrix<Real, Eigen::Dynamic, Eigen::Dynamic>;
  using VectorR = Eigen::Matrix<Real, Eigen::Dynamic, 1>;

  Oracle(int n, const algid::ChainConfig<double>& config)
      : n_(n),
        config_(config),
        rule_(static_cast<Real>(config.dt)),
        accel_(static_cast<std::size_t>(n)),
        force_(accel_.size()),
        dof_(static_cast<std::size_t>(n)) {
    reseed();
  }

  void reseed() {
    for (auto& c : accel_) c.reset();
    for (auto& c : force_) c.reset();
    for (auto& d : dof_) d = Dof{};
    samples_ = 0;
  }

  algid::Status update(const double* a, const double* u) {
    for (int i = 0; i < n_; ++i)
      if (!std::isfinite(a[i]) || !std::isfinite(u[i])) {
        reseed();
        return algid::Status::kBadInput;
      }
    bool advanced = false;
    for (int i = 0; i < n_; ++i) {
      advanced = accel_[static_cast<std::size_t>(i)].push(a[i], rule_);
      force_[static_cast<std::size_t>(i)].push(u[i], rule_);
    }
    ++samples_;
    if (!advanced) return algid::Status::kWarmup;
    const Real tau = static_cast<Real>(samples_ - P + 1) * static_cast<Real>(config_.dt);
    // Every signal's rows: [mass, damping, spring] of the accelerations, the right-hand side
    // of the forces, rows q = 0..3.
    std::vector<Eigen::Matrix<Real, 4, 3>> ya(static_cast<std::size_t>(n_));
    std::vector<Eigen::Matrix<Real, 4, 1>> uf(static_cast<std::size_t>(n_));
    for (int i = 0; i < n_; ++i) {
      Real J[kOrders + 1], F[kOrders + 1];
      for (int r = 0; r <= kOrders; ++r) {
        J[r] = accel_[static_cast<std::size_t>(i)].integral(r) / std::pow(tau, r);
        F[r] = force_[static_cast<std::size_t>(i)].integral(r) / std::pow(tau, r);
      }
      using algid::scaled_moment;
      auto& rows = ya[static_cast<std::size_t>(i)];
      for (int q = 0; q < 4; ++q) {
        rows(q, 0) = scaled_moment(J, 2, q) - 4 * scaled_moment(J, 1, q + 1) + 2 * scaled_moment(J, 0, q + 2);
        rows(q, 1) = scaled_moment(J, 2, q + 1) - 2 * scaled_moment(J, 1, q + 2);
        rows(q, 2) = scaled_moment(J, 2, q + 2);
        uf[static_cast<std::size_t>(i)](q) = scaled_moment(F, 2, q) - 4 * scaled_moment(F, 1, q + 1) +
                                             2 * scaled_moment(F, 0, q + 2);
      }
    }
    const Real h = static_cast<Real>(config_.dt);
    for (int i = 0; i < n_; ++i) {
      Dof& d = dof_[static_cast<std::size_t>(i)];
      const int m = reduced(i) ? 3 : 4;
      MatrixR S(m, m);
      VectorR s(m);
      const auto& self = ya[static_cast<std::size_t>(i)];
      for (int q = 0; q < m; ++q) {
        S(q, 0) = self(q, 0);
        S(q, 1) = self(q, 1);
        S(q, 2) = self(q, 2) - (i > 0 ? ya[static_cast<std::size_t>(i - 1)](q, 2) : Real(0));
        if (m == 4) S(q, 3) = self(q, 2) - (i + 1 < n_ ? ya[static_cast<std::size_t>(i + 1)](q, 2) : Real(0));
        s(q) = uf[static_cast<std::size_t>(i)](q);
      }
      const Eigen::FullPivLU<MatrixR> lu(S);
      const Real det = lu.determinant();
      d.theta_instant.setConstant(std::numeric_limits<double>::quiet_NaN());
      Real theta[4] = {0, 0, 0, 0};
      const bool solved = std::isfinite(static_cast<double>(det)) && det != Real(0);
      if (solved) {
        const VectorR phi = lu.solve(s);
        theta[0] = phi(0);
        theta[1] = phi(1) / tau;
        for (int j = 2; j < m; ++j) theta[j] = phi(j) / (tau * tau);
        for (int j = 0; j < m; ++j) d.theta_instant(j) = static_cast<double>(theta[j]);
      }
      // Hadamard ratio: columns to unit norm, then rows, |det| of the result.
      MatrixR E = S;
      for (int c = 0; c < m; ++c) E.col(c) /= E.col(c).norm();
      for (int r = 0; r < m; ++r) E.row(r) /= E.row(r).norm();
      const double had = static_cast<double>(std::abs(Eigen::FullPivLU<MatrixR>(E).determinant()));
      d.hadamard = std::isfinite(had) ? had : 0.0;
      d.instant_valid = samples_ >= config_.validity.min_samples && solved &&
                        d.hadamard >= config_.validity.min_hadamard;
      // Eq. 7: trapezoidal double integrals from t0 of the physical weights.
      Real x[5] = {0, 0, 0, 0, 0};
      if (d.instant_valid) {
        x[0] = std::abs(det) * std::pow(tau, m == 4 ? 19 : 12);
        for (int j = 0; j < m; ++j) x[1 + j] = x[0] * theta[j];
      }
      for (int j = 0; j < 5; ++j) {
        const Real i1 = d.i1[j] + h / 2 * (d.prev[j] + x[j]);
        d.i2[j] += h / 2 * (d.i1[j] + i1);
        d.i1[j] = i1;
        d.prev[j] = x[j];
      }
      d.theta.setConstant(std::numeric_limits<double>::quiet_NaN());
      if (d.i2[0] > 0)
        for (int j = 0; j < m; ++j) d.theta(j) = static_cast<double>(d.i2[1 + j] / d.i2[0]);
    }
    return algid::Status::kOk;
  }

  bool reduced(int i) const { return i == n_ - 1 && (n_ == 1 || config_.boundary == algid::Boundary::kFree); }
  Eigen::Vector4d theta(int i) const { return dof_[static_cast<std::size_t>(i)].theta; }
  Eigen::Vector4d theta_instant(int i) const { return dof_[static_cast<std::size_t>(i)].theta_instant; }
  double hadamard(int i) const { return dof_[static_cast<std::size_t>(i)].hadamard; }
  bool instant_valid(int i) const { return dof_[static_cast<std::size_t>(i)].instant_valid; }
  bool valid(int i) const { return dof_[static_cast<std::size_t>(i)].i2[0] > 0; }
  double mass(int i) const { return theta(i)(0); }
  double damping(int i) const { return theta(i)(1); }
  /// k_1 .. k_{n+1}, fused (see the file comment).
  double stiffness(int j) const {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (j == n_ && config_.boundary == algid::Boundary::kFree) return 0.0;
    const bool own = j < n_ && valid(j), left = j > 0 && valid(j - 1) && !reduced(j - 1);
    const double a = own ? theta(j)(2) : nan, b = left ? theta(j - 1)(3) : nan;
    if (own && left) return 0.5 * (a + b);
    return own ? a : b;
  }
  long samples() const { return samples_; }
  int dofs() const { return n_; }

 private:
  struct Dof {
    Eigen::Vector4d theta = Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
    Eigen::Vector4d theta_instant = Eigen::Vector4d::Constant(std::numeric_limits<double>::quiet_NaN());
    double hadamard = 0;
    bool instant_valid = false;
    Real i1[5] = {}, i2[5] = {}, prev[5] = {};  // [|det A|, |det A| theta_0 .. theta_3]
  };
  int n_;
  algid::ChainConfig<double> config_;
  Rule rule_;
  std::vector<ScalarChain<P, kOrders, Real>> accel_, force_;
  std::vector<Dof> dof_;
  long samples_ = 0;
};

}  // namespace algid_test
