#pragma once
// Baseline for the per-sample cost: recursive least squares with a forgetting factor for the
// same 4 parameters per DOF, theta_i = [m_i, c_i, k_i, k_{i+1}], on the regressor
// phi_i = [y_i, v_i, x_i - x_{i-1}, x_i - x_{i+1}] and target u_i (eq. 1 row i).
// It is handed velocities and displacements for free (the estimator derives everything from
// y and u), so its cost is a lower bound for an RLS pipeline on the same sensors.
#include <algid/types.hpp>

namespace algid_bench {

/// One DOF's RLS: theta += K (u - phi' theta), K = P phi / (lambda + phi' P phi),
/// P = (P - K phi' P) / lambda. About 110 flops per update.
template <class Scalar>
class Rls4 {
 public:
  Rls4() { reset(); }
  /// `lambda` forgetting factor in (0, 1]; `p0` initial covariance scale.
  Rls4(Scalar lambda, Scalar p0) : lambda_(lambda), p0_(p0) { reset(); }

  void reset() noexcept {
    p_ = algid::Matrix<Scalar, 4, 4>::Identity() * p0_;
    theta_.setZero();
  }

  /// @realtime no allocation, no throw
  void update(const Scalar* phi_ptr, Scalar target) noexcept {
    const Eigen::Map<const algid::Vector<Scalar, 4>> phi(phi_ptr);
    pphi_.noalias() = p_ * phi;
    const Scalar denom = lambda_ + phi.dot(pphi_);
    gain_ = pphi_ / denom;
    const Scalar err = target - phi.dot(theta_);
    theta_ += gain_ * err;
    p_.noalias() -= gain_ * pphi_.transpose();
    p_ *= Scalar(1) / lambda_;
  }

  const algid::Vector<Scalar, 4>& theta() const noexcept { return theta_; }

 private:
  Scalar lambda_ = Scalar(0.999);
  Scalar p0_ = Scalar(1e6);
  algid::Matrix<Scalar, 4, 4> p_;
  algid::Vector<Scalar, 4> theta_, pphi_, gain_;
};

}  // namespace algid_bench
