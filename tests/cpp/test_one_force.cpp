// One force, a whole chain: ChainEstimator with a force on one DOF only (fixed N and N = Dynamic).
//  - exact on closed-form polynomial trajectories (OneForceChainN, closed_form.hpp: every other
//    DOF's equation holds with u_i = 0 exactly): every mass, damping and spring within 1e-6
//    relative after 0.3 s of window, with the force on DOF 1 and on an interior DOF, for the
//    paper's Table 1 chain and random 4- and 6-DOF chains, walls and a free end; the forced
//    flags and the carried springs (one number on both sides of a spring a DOF took its scale through);
//  - a chain with no force at all has no scale: nothing valid, every estimate NaN;
//  - a DOF whose force appears later in the window counts as forced from then on (reseed() forgets it);
//  - n = 1 without force: NaN, never valid.
#include <algid/chain_estimator.hpp>

#include "check.hpp"
#include "closed_form.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using algid::Dynamic;
using algid_test::OneForceChainN;

// NaN (no estimate) counts as infinitely wrong
double rel(double est, double truth) {
  const double e = std::abs(est / truth - 1);
  return std::isnan(e) ? HUGE_VAL : e;
}

// Feed `samples` of the chain at dt = 1e-2 s; the worst relative error of every parameter at
// the end (the spring k_(n+1) = 0 of a free end checked as exactly 0).
template <class Est>
double run_exact(const OneForceChainN& truth, algid::Boundary boundary, const char* name, int samples = 40) {
  const int n = truth.n;
  typename Est::Config cfg;
  cfg.dt = 1e-2;
  cfg.boundary = boundary;
  cfg.validity.min_hadamard = 1e-12;  // polynomial trajectories are poorly conditioned
  Est est(cfg, n);
  std::vector<double> a(static_cast<std::size_t>(n)), u(a);
  for (int s = 0; s < samples; ++s) {
    for (int i = 0; i < n; ++i) {
      a[static_cast<std::size_t>(i)] = truth.accel(i, s * cfg.dt);
      u[static_cast<std::size_t>(i)] = truth.force(i, s * cfg.dt);
    }
    est.update(a.data(), u.data());
  }
  const bool free_end = boundary == algid::Boundary::kFree;
  double err = 0;
  for (int i = 0; i < n; ++i) {
    const std::size_t a_ = static_cast<std::size_t>(i);
    err = std::max({err, rel(est.mass()(i), truth.m[a_]), rel(est.damping()(i), truth.c[a_]),
                    rel(est.theta(i)(0), truth.m[a_]), rel(est.theta(i)(2), truth.k[a_])});
    CHECK(est.forced(i) == (i == truth.forced));
  }
  for (int j = 0; j < (free_end ? n : n + 1); ++j)
    err = std::max(err, rel(est.stiffness()(j), truth.k[static_cast<std::size_t>(j)]));
  if (free_end) CHECK(est.stiffness()(n) == 0.0);
  CHECK(est.all_valid());
  // The springs the scale passed through: both DOF's estimates are the same number (the
  // forced side's, carried), and it is the reported spring.
  for (int j = 1; j < n; ++j) {
    if (j - 1 >= truth.forced) CHECK(rel(est.theta(j)(2), est.theta(j - 1)(3)) < 1e-14);
    if (j <= truth.forced) CHECK(rel(est.theta(j - 1)(3), est.theta(j)(2)) < 1e-14);
  }
  std::printf("%s %s n=%d force on DOF %d only (%s): every parameter within %.2e after %.2f s\n",
              Est::kDofs == Dynamic ? "Dynamic" : "fixed", name, n, truth.forced + 1, free_end ? "free" : "fixed", err,
              (samples - Est::kDelay) * cfg.dt);
  return err;
}

template <int N>
void one_force_exact(const OneForceChainN& truth, algid::Boundary boundary, const char* name) {
  CHECK(run_exact<algid::ChainEstimator<N>>(truth, boundary, name) < 1e-6);
  CHECK(run_exact<algid::ChainEstimator<Dynamic>>(truth, boundary, name) < 1e-6);
}

template <int N>
void random_chain(unsigned seed) {
  for (const int forced : {0, N / 2, N - 1}) {
    one_force_exact<N>(OneForceChainN(N, forced, seed), algid::Boundary::kFixed, "random");
    one_force_exact<N>(OneForceChainN(N, forced, seed + 1, true), algid::Boundary::kFree, "random");
  }
}

// Without any force there is no scale: nothing valid, every estimate NaN (the walls' springs too).
void no_force_no_scale() {
  const OneForceChainN truth(4, 1, 7);
  algid::ChainEstimator<4>::Config cfg;
  cfg.dt = 1e-2;
  cfg.validity.min_hadamard = 1e-12;
  algid::ChainEstimator<4> est(cfg);
  const double zero[4] = {0, 0, 0, 0};
  for (int s = 0; s < 40; ++s) {
    double a[4];
    for (int i = 0; i < 4; ++i) a[i] = truth.accel(i, s * cfg.dt);
    est.update(a, zero);
  }
  CHECK(!est.valid().any());
  CHECK(est.mass().array().isNaN().all() && est.damping().array().isNaN().all());
  CHECK(est.stiffness().array().isNaN().all());
  for (int i = 0; i < 4; ++i) CHECK(!est.forced(i));
  // one DOF alone has no neighbour to take a scale from
  algid::ChainEstimator<1>::Config one;
  one.dt = 1e-2;
  algid::ChainEstimator<1> single(one);
  for (int s = 0; s < 40; ++s) {
    const double a = truth.accel(0, s * one.dt), u = 0;
    single.update(&a, &u);
  }
  CHECK(!single.all_valid() && std::isnan(single.mass()(0)) && std::isnan(single.stiffness()(0)));
}

// A force that appears after 0.15 s: until then the chain has no scale (nothing valid), and
// its DOF counts as forced from the sample it appears at (the record before it is not a motion
// of the chain under that force, so the estimates after it are not checked).
void late_force() {
  const OneForceChainN truth(3, 1, 11);
  using Est = algid::ChainEstimator<3>;
  Est::Config cfg;
  cfg.dt = 1e-2;
  cfg.validity.min_hadamard = 1e-12;
  Est est(cfg);
  bool unscaled_before = true, forced_from = true;
  for (int s = 0; s < 30; ++s) {
    double a[3], u[3];
    for (int i = 0; i < 3; ++i) {
      a[i] = truth.accel(i, s * cfg.dt);
      u[i] = s < 15 ? 0.0 : truth.force(i, s * cfg.dt);
    }
    est.update(a, u);
    if (s < 15) unscaled_before &= !est.valid().any() && est.mass().array().isNaN().all();
    forced_from &= est.forced(1) == (s >= 15) && !est.forced(0) && !est.forced(2);
  }
  CHECK(unscaled_before);
  CHECK(forced_from);
  est.reseed();
  CHECK(!est.forced(1));
}

}  // namespace

int main() {
  // The paper's Table 1 chain, the force on DOF 1, then on DOF 2 (interior), then DOF 3.
  const std::vector<double> m{2.0, 2.5, 3.0}, c{5.5, 5.0, 4.5}, k{1000, 900, 900, 700};
  for (const int forced : {0, 1, 2})
    one_force_exact<3>(OneForceChainN(m, c, k, forced, 1), algid::Boundary::kFixed, "Table 1");
  random_chain<4>(40);
  random_chain<6>(60);
  no_force_no_scale();
  late_force();
  return algid_test::finish("test_one_force");
}
