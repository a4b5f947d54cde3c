#pragma once
/// @file joint_sum.hpp
/// Aggregation of weak-form windows by their information: the sum of the GLS-weighted
/// windows' normal equations since the start (with `horizon_s` forgetting), solved for all
/// parameters at once (JointSum), and the pair of such sums over the short and the long
/// windows from which each parameter is reported (JointSums). A ring of the newest windows'
/// systems lets a restart of one parameter (a change) take them out again and marginalise the
/// parameter out of the rest (docs/continuous.md).
///
/// Storage: per sum, four (3n+1)^2 matrices and a ring of `block` hops of window systems,
/// allocated by the constructor (weak-form windows only).

#include "algid/detail/robust.hpp"
#include "algid/detail/storage.hpp"
#include "algid/types.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

namespace algid {

/// The summed normal equations of one window length (see the file comment).
class JointSum {
 public:
  /// A sum of `params` parameters whose ring holds `ring` windows; `forget` per window (1: none).
  JointSum(int params, int ring, double forget) : ldlt_(params), size_(ring), forget_(forget), params_(params) {
    normal_.setZero(params, params);
    inverse_.setZero(params, params);
    rhs_.setZero(params);
    solution_.setZero(params);
    column_.setZero(params);
    ring_normal_.resize(ring);
    ring_rhs_.resize(ring);
    fresh_.resize(params);
    trusted_.resize(params);
    for (int r = 0; r < ring; ++r) {
      ring_normal_[r].setZero(params, params);
      ring_rhs_[r].setZero(params);
    }
  }

  /// Forget every window. @realtime no allocation, no throw
  void clear() noexcept {
    normal_.setZero();
    rhs_.setZero();
    fresh_.fill(0);
    trusted_.fill(true);
    head_ = count_ = stage_ = 0;
    valid_ = false;
  }

  /// A weighted window's normal equations join the sum; a parameter restarted a ring of windows
  /// ago is forgotten once more except for the newest ring minus `stagger` windows and trusted
  /// again (its prior at `track`). @realtime no allocation, no throw
  template <class Track>
  void add(const Eigen::MatrixXd& normal, const Eigen::VectorXd& rhs, const Track& track, int stagger) noexcept {
    if (forget_ < 1.0) {
      normal_ *= forget_;
      rhs_ *= forget_;
      for (int r = 0; r < size_; ++r) {
        ring_normal_[r] *= forget_;
        ring_rhs_[r] *= forget_;
      }
    }
    const int r = head_;
    ring_normal_[r] = normal;
    ring_rhs_[r] = rhs;
    head_ = (head_ + 1) % size_;
    count_ = std::min(count_ + 1, size_);
    normal_ += normal;
    rhs_ += rhs;
    for (int j = 0; j < params_; ++j) {
      if (trusted_[j] || ++fresh_[j] < size_) continue;
      forget(j, size_ - stagger, static_cast<double>(track(j)));
      trusted_[j] = true;
    }
  }

  /// Solve in one go: factor, solution, inverse. @realtime no allocation, no throw
  void solve() noexcept {
    ldlt_.compute(normal_);
    publish();
    stage_ = 0;
  }

  /// Schedule the solve over the next two samples (see step()).
  void schedule() noexcept { stage_ = 1; }

  /// One O(P^3) part of a scheduled solve: the factorisation, then the solution and the inverse;
  /// true when the solution is new. @realtime no allocation, no throw
  bool step() noexcept {
    if (stage_ == 0) return false;
    if (stage_ == 1) {
      ldlt_.compute(normal_);
      stage_ = 2;
      return false;
    }
    publish();
    stage_ = 0;
    return true;
  }

  /// Parameter j restarted (step or drift): the windows of the ring (the newest, which may
  /// straddle the change and fit no single value of j) leave the sum for every parameter; it
  /// forgets all it knew of j (prior at `prior`), and j is not trusted until a ring of windows
  /// has arrived since; the sum is solved again. @realtime no allocation, no throw
  void restart(int j, double prior) noexcept {
    for (int age = 0; age < count_; ++age) {
      const int r = slot(age);
      normal_ -= ring_normal_[r];
      rhs_ -= ring_rhs_[r];
      ring_normal_[r].setZero();
      ring_rhs_[r].setZero();
    }
    forget(j, 0, prior);
    fresh_[j] = 0;
    trusted_[j] = false;
    solve();
  }

  /// True if the solution exists and parameter j is reported from it.
  bool reports(int j) const noexcept { return valid_ && trusted_[j]; }
  /// Solution for parameter j [parameter units].
  double solution(int j) const noexcept { return solution_(j); }
  /// Diagonal of the inverse normal matrix for j (the variance of a GLS sum of independent windows).
  double variance(int j) const noexcept { return inverse_(j, j); }

 private:
  void publish() noexcept {
    valid_ = ldlt_.info() == Eigen::Success && ldlt_.vectorD().minCoeff() > 0.0;
    if (valid_) {
      solution_ = rhs_;
      ldlt_.solveInPlace(solution_);
      inverse_.setIdentity();
      ldlt_.solveInPlace(inverse_);
      valid_ = solution_.allFinite();
    }
  }

  int slot(int age) const noexcept {  // age 0: the newest window
    return ((head_ - 1 - age) % size_ + size_) % size_;
  }

  // Take the `recent` newest windows out, marginalise parameter j out of the rest (its old
  // information is void, the others' is kept: the Schur complement), pin j by a negligible
  // prior at `prior` (so the system stays definite), put the recent windows back.
  void forget(int j, int recent, double prior_value) noexcept {
    recent = std::min(recent, count_);
    for (int age = 0; age < recent; ++age) {
      const int r = slot(age);
      normal_ -= ring_normal_[r];
      rhs_ -= ring_rhs_[r];
    }
    const double d = normal_(j, j);
    if (d > 0.0) {
      column_ = normal_.col(j);
      const double bj = rhs_(j);
      for (int b = 0; b < params_; ++b) {
        for (int a = 0; a < params_; ++a) normal_(a, b) -= column_(a) * column_(b) / d;
        rhs_(b) -= column_(b) * bj / d;
      }
    }
    normal_.row(j).setZero();
    normal_.col(j).setZero();
    const double prior = 1e-12 * (d > 0.0 ? d : 1.0);
    normal_(j, j) = prior;
    rhs_(j) = prior * prior_value;
    for (int age = 0; age < recent; ++age) {
      const int r = slot(age);
      normal_ += ring_normal_[r];
      rhs_ += ring_rhs_[r];
    }
  }

  Eigen::MatrixXd normal_, inverse_;
  Eigen::VectorXd rhs_, solution_, column_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  detail::Storage<Eigen::MatrixXd, Dynamic> ring_normal_;
  detail::Storage<Eigen::VectorXd, Dynamic> ring_rhs_;
  detail::Storage<int, Dynamic> fresh_;     // per parameter: windows since its restart
  detail::Storage<bool, Dynamic> trusted_;  // per parameter: the joint estimate is reported
  int head_ = 0, count_ = 0, size_ = 0;
  int stage_ = 0;  // solve pending: 1 factor next sample, 2 solve next sample, 0 none
  double forget_ = 1.0;
  int params_ = 0;
  bool valid_ = false;
};

/// Configuration of the joint sums (weak-form windows).
template <class Scalar>
struct JointConfig {
  bool joint = true;  ///< estimate from the summed window normal equations (false: from the tracks)
  /// sigma = sqrt(diag(N^-1) / joint_efficiency), for the overlap of the windows' information, (0, 1]
  Scalar joint_efficiency = Scalar(0.3);
  /// A window whose misfit (WeakFormWindows::misfit(), the weighted residual per degree of
  /// freedom) exceeds this many times the larger of 1 and the median misfit of the 16 windows
  /// before it stays out of the joint normal equations (finite garbage, a transient the chain
  /// does not describe, a window straddling a change); the tracks still see it. 0: off.
  Scalar misfit_ratio = Scalar(30);
};

/// The joint sums of the short and the long weak-form windows, and the misfit screen in front
/// of them: each parameter is reported from the sum (of those that trust it) with the smaller
/// variance.
template <class Scalar>
class JointSums {
 public:
  /// Sums of `params` parameters for windows of `short_hop` and (if > 0) `long_hop` samples
  /// between results; a ring spans `block` short hops (and more than 2K + 1 windows of its own);
  /// forgetting with `horizon_s` [s] (0: none). Allocates.
  JointSums(const JointConfig<Scalar>& config, int params, long short_hop, long long_hop, int block, int stagger,
            Scalar horizon_s, Scalar dt, bool amortize)
      : config_(config), params_(params), stagger_(stagger), amortize_(amortize) {
    if (!config.joint) return;
    sums_[0] = make(short_hop, short_hop, block, horizon_s, dt);
    if (long_hop > 0) sums_[1] = make(long_hop, short_hop, block, horizon_s, dt);
  }

  /// Forget every window. @realtime no allocation, no throw
  void reset() noexcept {
    for (auto& J : sums_)
      if (J) J->clear();
    misfits_ = MisfitRing{};
    screened_ = 0;
  }

  /// A window of kind `which` (0 short, 1 long) with result `x`, normal equations and misfit:
  /// if it passes the misfit screen, is weighted and every estimated parameter is finite, it
  /// joins its sum; true if the sum was solved at once (amortize off).
  /// @realtime no allocation, no throw
  template <class Windows, class Estimated, class Track>
  bool add(int which, const Windows& w, const Estimated& estimated, const Track& track) noexcept {
    JointSum* J = sums_[static_cast<std::size_t>(which)].get();
    if (!J || !fits(w.misfit())) return false;
    const auto& x = w.result();
    for (int j = 0; j < params_; ++j)
      if (estimated(j) && !std::isfinite(x(j))) return false;
    if (!w.result_weighted()) return false;
    J->add(w.normal(), w.rhs(), track, stagger_);
    if (amortize_) {
      J->schedule();  // factored on the next sample, solved on the one after
      return false;
    }
    J->solve();
    return true;
  }

  /// One O(P^3) part of each scheduled solve; true if a solution is new. @realtime no allocation, no throw
  bool step() noexcept {
    bool solved = false;
    for (auto& J : sums_)
      if (J) solved = J->step() || solved;
    return solved;
  }

  /// Parameter j restarted: both sums forget it (prior at `prior`) and are solved again; true
  /// if there is a sum. @realtime no allocation, no throw
  bool restart(int j, double prior) noexcept {
    for (auto& J : sums_)
      if (J) J->restart(j, prior);
    return sums_[0] != nullptr;
  }

  /// The sum that reports parameter j (nullptr: none, the tracks report it).
  const JointSum* best(int j) const noexcept {
    const JointSum* best = nullptr;
    for (const auto& J : sums_)
      if (J && J->reports(j) && (!best || J->variance(j) < best->variance(j))) best = J.get();
    return best;
  }

  /// Estimate and one-sigma uncertainty of parameter j from the best sum; false if none reports it.
  bool report(int j, Scalar& estimate, Scalar& sigma) const noexcept {
    const JointSum* J = best(j);
    if (!J) return false;
    estimate = static_cast<Scalar>(J->solution(j));
    sigma = static_cast<Scalar>(std::sqrt(J->variance(j) / static_cast<double>(config_.joint_efficiency)));
    return true;
  }

  /// True if parameter j is reported from the long windows' sum.
  bool from_long(int j) const noexcept { return sums_[1] && best(j) == sums_[1].get(); }
  /// Windows kept out of the sums by the misfit screen since reset().
  long screened() const noexcept { return screened_; }

 private:
  static constexpr int kMisfits = 16;
  struct MisfitRing {
    std::array<double, kMisfits> value{};
    int head = 0, count = 0;
  };

  std::unique_ptr<JointSum> make(long hop, long short_hop, int block, Scalar horizon_s, Scalar dt) const {
    const long ring = (block * short_hop + hop - 1) / hop;
    const double forget = horizon_s > Scalar(0)
                              ? std::exp(-static_cast<double>(hop) * static_cast<double>(dt / horizon_s))
                              : 1.0;
    return std::make_unique<JointSum>(params_, static_cast<int>(std::max<long>(ring, 2 * stagger_ + 1)), forget);
  }

  // The misfit screen: false if the window fits far worse than the windows before it, short
  // and long alike (a misfit is per degree of freedom: about 1 for both); every finite misfit
  // joins the ring of the newest kMisfits. One ring: the long windows' first weighted ones are
  // compared with the short windows before them, not with each other.
  bool fits(double misfit) noexcept {
    if (!std::isfinite(misfit)) return true;  // unweighted or failed: add() decides
    MisfitRing& ring = misfits_;
    double reference = 1.0;
    if (ring.count > 0) {
      std::copy(ring.value.begin(), ring.value.begin() + ring.count, scratch_.begin());
      reference = std::max(reference, detail::median_inplace(scratch_.data(), ring.count));
    }
    ring.value[static_cast<std::size_t>(ring.head)] = misfit;
    ring.head = (ring.head + 1) % kMisfits;
    ring.count = std::min(ring.count + 1, kMisfits);
    const double ratio = static_cast<double>(config_.misfit_ratio);
    const bool ok = !(ratio > 0.0 && misfit > ratio * reference);
    if (!ok) ++screened_;
    return ok;
  }

  JointConfig<Scalar> config_;
  int params_;
  int stagger_;
  bool amortize_;
  std::array<std::unique_ptr<JointSum>, 2> sums_;  // the short windows' and the long windows'
  MisfitRing misfits_{};
  std::array<double, kMisfits> scratch_{};
  long screened_ = 0;
};

}  // namespace algid
