// ChainEstimator, fixed N and N = Dynamic (the number of DOF given to the constructor):
//  - agrees with the scalar test oracle (oracle.hpp: integrator chains as plain loops, eq. 5
//    from the scaled moments, FullPivLU instead of Cramer, eq. 7 as physical trapezoidal double
//    integrals) to rounding on a multisine record, every sample, fixed walls and a free end,
//    N = 1, 2, 3, 5, 11 and Dynamic n = 1, 2, 3, 5, 11, 30 (tolerances at oracle_case), and its
//    instantaneous solutions are as accurate as the oracle's against the oracle in long double;
//  - eq. 7's weighting of a 3x3 system (a known header bug, ratio_decay<3>) on records the model
//    does not fit, where the weighting shows;
//  - is exact on closed-form polynomial trajectories: fixed walls, a free right end, n = 1
//    (k_1 + k_2), both estimates of an interior spring, at the same sizes fixed and Dynamic and
//    Dynamic n = 11, 30;
//  - multisine accuracy, bad samples and reseed, a constant force (not identifiable), and the
//    configuration checks (dt, the number of DOF).
#include <algid/chain_estimator.hpp>

#include "check.hpp"
#include "closed_form.hpp"
#include "oracle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using algid::Dynamic;

double rel(double est, double truth) { return std::abs(est / truth - 1); }

template <class Est>
std::string label(int n) {
  return (Est::kDofs == Dynamic ? std::string("Dynamic n=") : std::string("N=")) + std::to_string(n);
}

// Exactness on polynomial trajectories: the discretisation is exact, so the instantaneous
// Cramer solution differs from the truth by rounding only, amplified by the conditioning
// (polynomial trajectories excite the chain poorly: Hadamard ratios of 1e-12 .. 1e-6).
// Checked: |error| * hadamard stays at rounding level (<= 1e-8) at every sample, and the eq. 7
// estimate at the end of the record is within 3e-7 (1e-6 at n = 30).
template <class Est>
void exact_case(int n, unsigned seed, algid::Boundary boundary) {
  const bool free_end = boundary == algid::Boundary::kFree;
  const bool sum_only = n == 1 && !free_end;
  const algid_test::PolynomialChainN truth(n, seed, free_end);
  typename Est::Config cfg;
  cfg.dt = 1e-2;
  cfg.boundary = boundary;
  cfg.validity.min_hadamard = 1e-12;  // polynomial trajectories are poorly conditioned
  Est est(cfg, n);
  CHECK(est.dofs() == n);
  const auto k = [&](int j) { return truth.k[static_cast<std::size_t>(j)]; };
  double worst_scaled = 0;
  std::vector<double> a(static_cast<std::size_t>(n)), u(a);
  for (int s = 0; s < 200; ++s) {
    for (int i = 0; i < n; ++i) {
      a[static_cast<std::size_t>(i)] = truth.accel(i, s * cfg.dt);
      u[static_cast<std::size_t>(i)] = truth.force(i, s * cfg.dt);
    }
    est.update(a.data(), u.data());
    for (int i = 0; i < n; ++i) {
      const auto th = est.theta_instant(i);
      if (std::isnan(th(0))) continue;
      const double kl = sum_only ? k(0) + k(1) : k(i);
      double e = std::max({rel(th(0), truth.m[static_cast<std::size_t>(i)]),
                           rel(th(1), truth.c[static_cast<std::size_t>(i)]), rel(th(2), kl)});
      if (!std::isnan(th(3))) e = std::max(e, rel(th(3), k(i + 1)));
      worst_scaled = std::max(worst_scaled, e * est.hadamard(i));
    }
  }
  double final_err = 0;
  for (int i = 0; i < n; ++i)
    final_err = std::max({final_err, rel(est.mass()(i), truth.m[static_cast<std::size_t>(i)]),
                          rel(est.damping()(i), truth.c[static_cast<std::size_t>(i)])});
  for (int j = 0; j < (sum_only ? 1 : n); ++j)
    final_err = std::max(final_err, rel(est.stiffness()(j), sum_only ? k(0) + k(1) : k(j)));
  if (!free_end && !sum_only) final_err = std::max(final_err, rel(est.stiffness()(n), k(n)));
  std::printf("%s %s: exact case, max |error| * hadamard %.2e, final eq. 7 error %.2e\n", label<Est>(n).c_str(),
              free_end ? "free" : "fixed", worst_scaled, final_err);
  CHECK(worst_scaled < 1e-8);
  // 0.2 s of window: rounding-level, 1e-11 .. 1.2e-7 for n <= 11 (N = 5 in an -march=x86-64-v3
  // build, where the chain products fuse multiply-adds; 1.5e-8 with the portable flags), and
  // 3.5e-7 at n = 30 (more DOF, more poorly conditioned systems: the worst of them).
  CHECK(final_err < (n <= 11 ? 3e-7 : 1e-6));
  CHECK(est.all_valid());
  CHECK(est.valid().all() && est.valid().size() == n);
  CHECK(est.stiffness().size() == n + 1 && est.mass().size() == n);
  if (free_end) CHECK(est.stiffness()(n) == 0.0);
  if (free_end) CHECK(std::isnan(est.theta(n - 1)(3)) && std::isnan(est.theta_instant(n - 1)(3)));
  if (sum_only) CHECK(std::isnan(est.stiffness()(1)));
  // Both estimates of an interior spring are reported and agree with the truth.
  for (int j = 1; j < n; ++j) {
    CHECK(rel(est.theta(j - 1)(3), k(j)) < 1e-7);
    CHECK(rel(est.theta(j)(2), k(j)) < 1e-7);
  }
}

template <int N>
void exact_both(unsigned seed, algid::Boundary boundary) {
  exact_case<algid::ChainEstimator<N>>(N, seed, boundary);
  exact_case<algid::ChainEstimator<Dynamic>>(N, seed, boundary);
}

// Accuracy on closed-form multisine trajectories at 1 kHz (not exact: O(h^8)).
template <class Est>
void multisine_case(int n, unsigned seed) {
  const algid_test::SineChainN truth(n, seed);
  typename Est::Config cfg;
  Est est(cfg, n);
  double err_50ms = 0, err_end = 0;
  const algid_test::Samples rec(truth, 507, cfg.dt);
  for (int s = 0; s <= 506; ++s) {
    est.update(rec.a(s), rec.u(s));
    if (s == 56 || s == 506) {
      double e = 0;
      for (int i = 0; i < n; ++i)
        e = std::max({e, rel(est.mass()(i), truth.m[static_cast<std::size_t>(i)]),
                      rel(est.damping()(i), truth.c[static_cast<std::size_t>(i)])});
      if (n == 1) {
        e = std::max(e, rel(est.stiffness()(0), truth.k[0] + truth.k[1]));  // only the sum
      } else {
        for (int j = 0; j <= n; ++j) e = std::max(e, rel(est.stiffness()(j), truth.k[static_cast<std::size_t>(j)]));
      }
      (s == 56 ? err_50ms : err_end) = e;
    }
  }
  std::printf("%s multisine at 1 kHz: max error %.2e at t0 + 0.05 s, %.2e at t0 + 0.5 s\n", label<Est>(n).c_str(),
              err_50ms, err_end);
  CHECK(err_50ms < 1e-2);
  CHECK(err_end < 1e-6);
}

// Figures over every oracle case, printed at the end (the report's agreement figures).
struct OracleFigures {
  double instant_scaled = 0;  // max |relative difference| * Hadamard ratio, theta_instant
  double instant_1e6 = 0;     // max relative difference of theta_instant where Hadamard > 1e-6
  double instant_1e2 = 0;     // ... where Hadamard > 1e-2
  double hadamard = 0;        // max |difference| of the Hadamard ratios
  double eq7 = 0;             // max relative difference of eq. 7 from t0 + 100 ms (4x4 DOF)
  double eq7_reduced = 0;     // ... of the 3x3 DOF (n = 1, the last DOF at a free end)
  double eq7_early = 0;       // ... of any DOF from t0 + 30 ms
  double accuracy = 0;        // max |relative error| * Hadamard ratio of theta_instant against a long double oracle
  double accuracy_oracle = 0; // ... of the double oracle (the same figure for a plain LU implementation)
  long mismatches = 0;        // flags, statuses, NaN patterns
  void merge(const OracleFigures& o) {
    instant_scaled = std::max(instant_scaled, o.instant_scaled);
    instant_1e6 = std::max(instant_1e6, o.instant_1e6);
    instant_1e2 = std::max(instant_1e2, o.instant_1e2);
    hadamard = std::max(hadamard, o.hadamard);
    eq7 = std::max(eq7, o.eq7);
    eq7_reduced = std::max(eq7_reduced, o.eq7_reduced);
    eq7_early = std::max(eq7_early, o.eq7_early);
    accuracy = std::max(accuracy, o.accuracy);
    accuracy_oracle = std::max(accuracy_oracle, o.accuracy_oracle);
    mismatches += o.mismatches;
  }
};
OracleFigures g_oracle;

double rel_diff(double a, double b) { return a == b ? 0.0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

// The estimator against the oracle on a record, every sample (a bad sample and a reseed in the
// middle: both restart). Equal: statuses, samples(), instant_valid(), valid(), the NaN pattern
// of every value. To rounding, where rounding is amplified by the conditioning of eq. 5:
//  - theta_instant: |relative difference| * Hadamard ratio <= 5e-10 at every sample, and the
//    relative difference <= 1e-9 where the Hadamard ratio exceeds 1e-2. (Not 1e-9 where it
//    exceeds 1e-6: there the estimator and the double oracle are both off by up to ~3e-6 from
//    the long double oracle, the double rounding of S's entries amplified by the conditioning:
//    no double implementation agrees better; the "accuracy" figures below show it.)
//  - the Hadamard ratio to 1e-9 absolute;
//  - eq. 7 (theta, mass(), damping(), stiffness()) to 1e-9 relative from t0 + 100 ms, when the
//    well-conditioned instants dominate the double integrals (before that, the first trusted
//    instants carry rounding amplified as above: the worst from t0 + 30 ms is printed and
//    bounded by 1e-6). The 3x3 DOF (n = 1, the last at a free end) within 1e-8 only:
//    ratio_decay<3> returns (prev_tau / tau)^9, not ^12 (see ratio_decay_exponents in
//    test_lanes.cpp), so their eq. 7 weighs the instants differently from the paper's;
//    model_mismatch_weighting() shows it where it matters.
// Accuracy: theta_instant against the same oracle in long double (64-bit mantissa), where it is
// the exact solution of the same discretisation to ~1e-19 x conditioning: |relative error| *
// Hadamard ratio <= 5e-10 for the estimator (Cramer's rule), printed next to the double oracle's
// (LU) figure.
// `mismatch`: the record comes from a chain with one more spring or DOF than the estimator's
// model (the instants then vary, and eq. 7's weighting shows).
template <class Est>
OracleFigures oracle_case(int n, algid::Boundary boundary, unsigned seed, bool mismatch = false, bool report = true) {
  const bool free_end = boundary == algid::Boundary::kFree;
  typename Est::Config cfg;
  cfg.boundary = boundary;
  Est est(cfg, n);
  algid_test::Oracle<8> oracle(n, cfg);
  algid_test::Oracle<8, long double> exact(n, cfg);
  constexpr long T = 700, kBad = 330, kReseed = 520, kFrom = 100, kEarly = 30;
  // A free end's chain has k_{n+1} = 0 (with a mismatch, a wall); with walls and a mismatch,
  // the record of the first n DOF of an (n + 1)-DOF chain.
  const algid_test::SineChainN truth(mismatch && !free_end ? n + 1 : n, seed, free_end && !mismatch);
  algid_test::Samples full(truth, T, cfg.dt);
  algid_test::Samples rec = full;
  rec.n = n;
  for (long s = 0; s < T; ++s)
    for (int i = 0; i < n; ++i) {
      rec.accel[static_cast<std::size_t>(s * n + i)] = full.accel[static_cast<std::size_t>(s * full.n + i)];
      rec.force[static_cast<std::size_t>(s * n + i)] = full.force[static_cast<std::size_t>(s * full.n + i)];
    }
  rec.accel.resize(static_cast<std::size_t>(T * n));
  rec.force.resize(static_cast<std::size_t>(T * n));
  rec.force[static_cast<std::size_t>(kBad * n + n - 1)] = std::numeric_limits<double>::quiet_NaN();
  OracleFigures f;
  long compared_instant = 0, compared_eq7 = 0, t0 = 0;
  const auto nan_mismatch = [&](double a, double b) { return std::isnan(a) != std::isnan(b); };
  // eq. 7 value of DOF i (i < 0: not tied to a 3x3 DOF)
  const auto eq7 = [&](double a, double b, bool reduced, long since) {
    f.mismatches += nan_mismatch(a, b);
    if (std::isnan(a) || std::isnan(b)) return;
    const double d = rel_diff(a, b);
    if (since >= kEarly) f.eq7_early = std::max(f.eq7_early, d);
    if (since < kFrom) return;
    ++compared_eq7;
    (reduced ? f.eq7_reduced : f.eq7) = std::max(reduced ? f.eq7_reduced : f.eq7, d);
  };
  for (long s = 0; s < T; ++s) {
    if (s == kReseed) {
      est.reseed();
      oracle.reseed();
      exact.reseed();
      t0 = s;
    }
    const algid::Status got = est.update(rec.a(s), rec.u(s)), want = oracle.update(rec.a(s), rec.u(s));
    exact.update(rec.a(s), rec.u(s));
    f.mismatches += got != want;
    if (got == algid::Status::kBadInput) t0 = s + 1;
    f.mismatches += est.samples() != oracle.samples();
    const long since = s - t0;
    for (int i = 0; i < n; ++i) {
      f.mismatches += est.instant_valid(i) != oracle.instant_valid(i);
      f.mismatches += est.valid()(i) != oracle.valid(i);
      const auto ti = est.theta_instant(i), to = oracle.theta_instant(i), te = exact.theta_instant(i);
      const double h = oracle.hadamard(i);
      for (int j = 0; j < 4; ++j) {
        if (std::isnan(te(j)) || std::isnan(ti(j)) || std::isnan(to(j))) continue;
        f.accuracy = std::max(f.accuracy, std::abs(ti(j) - te(j)) / std::abs(te(j)) * exact.hadamard(i));
        f.accuracy_oracle = std::max(f.accuracy_oracle, std::abs(to(j) - te(j)) / std::abs(te(j)) * exact.hadamard(i));
      }
      f.hadamard = std::max(f.hadamard, std::abs(est.hadamard(i) - h));
      for (int j = 0; j < 4; ++j) {
        f.mismatches += nan_mismatch(ti(j), to(j));
        if (std::isnan(ti(j)) || std::isnan(to(j))) continue;
        const double d = rel_diff(ti(j), to(j));
        f.instant_scaled = std::max(f.instant_scaled, d * h);
        if (h > 1e-6) f.instant_1e6 = std::max(f.instant_1e6, d);
        if (h > 1e-2) f.instant_1e2 = std::max(f.instant_1e2, d);
        ++compared_instant;
      }
      const bool reduced = oracle.reduced(i);
      for (int j = 0; j < 4; ++j) eq7(est.theta(i)(j), oracle.theta(i)(j), reduced, since);
      eq7(est.mass()(i), oracle.mass(i), reduced, since);
      eq7(est.damping()(i), oracle.damping(i), reduced, since);
    }
    for (int j = 0; j <= n; ++j) eq7(est.stiffness()(j), oracle.stiffness(j), j < n && oracle.reduced(j), since);
  }
  if (report)
    std::printf(
        "%s %s%s vs oracle: theta_instant |rel| * hadamard %.2e, rel %.2e (hadamard > 1e-2), %.2e (> 1e-6); "
        "hadamard %.2e; eq. 7 from t0 + 100 ms %.2e (3x3 DOF %.2e), from t0 + 30 ms %.2e; %ld mismatches; "
        "vs long double: |rel| * hadamard %.2e (double LU oracle %.2e)\n",
        label<Est>(n).c_str(), free_end ? "free" : "fixed", mismatch ? " model mismatch" : "", f.instant_scaled,
        f.instant_1e2, f.instant_1e6, f.hadamard, f.eq7, f.eq7_reduced, f.eq7_early, f.mismatches, f.accuracy,
        f.accuracy_oracle);
  CHECK(f.mismatches == 0);
  CHECK(compared_instant > 500 * n);
  CHECK(compared_eq7 > 500 * n);
  CHECK(f.instant_scaled < 5e-10);
  CHECK(f.instant_1e2 < 1e-9);
  CHECK(f.hadamard < 1e-9);
  CHECK(f.eq7 < 1e-9);
  CHECK(f.accuracy < 5e-10);
  if (!mismatch) {
    CHECK(f.eq7_reduced < 1e-8);  // 1e-9 once ratio_decay<3> is fixed (see above)
    CHECK(f.eq7_early < 1e-6);
    CHECK(est.all_valid());
    g_oracle.merge(f);
  }
  return f;
}

template <int N>
void oracle_fixed(unsigned seed) {
  oracle_case<algid::ChainEstimator<N>>(N, algid::Boundary::kFixed, seed);
  oracle_case<algid::ChainEstimator<N>>(N, algid::Boundary::kFree, seed + 100);
}

void oracle_dynamic(int n, unsigned seed) {
  oracle_case<algid::ChainEstimator<Dynamic>>(n, algid::Boundary::kFixed, seed);
  oracle_case<algid::ChainEstimator<Dynamic>>(n, algid::Boundary::kFree, seed + 100);
}

// Eq. 7's weighting, where it matters: records from a chain the model does not describe (a wall
// behind what the estimator takes for a free end; for n = 1, the first DOF of two), so the
// instantaneous solutions of the last DOF wander and eq. 7 depends on how they are weighed. The
// paper weighs instant tau by |det A| = |det S| tau^q, q = 12 for a 3x3 system: ChainEstimator
// carries its scaled integrals with ratio_decay<3>, which returns (prev_tau / tau)^9 (a known
// header bug), so its 3x3 DOF disagree with the oracle by 1e-2 .. 1 here, while its 4x4 DOF
// agree to 1e-9.
void model_mismatch_weighting() {
  double worst = 0;
  worst = std::max(worst, oracle_case<algid::ChainEstimator<1>>(1, algid::Boundary::kFixed, 301, true).eq7_reduced);
  worst = std::max(worst,
                   oracle_case<algid::ChainEstimator<Dynamic>>(1, algid::Boundary::kFixed, 301, true).eq7_reduced);
  worst = std::max(worst, oracle_case<algid::ChainEstimator<3>>(3, algid::Boundary::kFree, 303, true).eq7_reduced);
  worst = std::max(worst,
                   oracle_case<algid::ChainEstimator<Dynamic>>(5, algid::Boundary::kFree, 305, true).eq7_reduced);
  CHECK(worst < 1e-9);
}

template <class Est>
void bad_samples_and_reseed(int n) {
  const algid_test::SineChainN truth(n, 11);
  typename Est::Config cfg;
  Est est(cfg, n);
  const algid_test::Samples rec(truth, 400, cfg.dt);
  for (int s = 0; s < 100; ++s) est.update(rec.a(s), rec.u(s));
  CHECK(est.all_valid());
  std::vector<double> bad(static_cast<std::size_t>(n), 1.0), ok(bad);
  bad[static_cast<std::size_t>(n / 2)] = std::numeric_limits<double>::quiet_NaN();
  CHECK(est.update(bad.data(), ok.data()) == algid::Status::kBadInput);
  CHECK(!est.valid().any());
  for (int i = 0; i < n; ++i) CHECK(std::isnan(est.mass()(i)) && std::isnan(est.theta(i)(0)) && !est.instant_valid(i));
  CHECK(est.samples() == 0 && est.window() == 0.0);
  bad[static_cast<std::size_t>(n / 2)] = std::numeric_limits<double>::infinity();
  CHECK(est.update(ok.data(), bad.data()) == algid::Status::kBadInput);
  // After a reseed the estimator restarts at the next sample, from any state of the system:
  // no initial conditions are needed (here t0 = 0.1 s into the trajectory).
  double worst = 0;
  for (int s = 100; s < 400; ++s) {
    const algid::Status st = est.update(rec.a(s), rec.u(s));
    CHECK(st == (s - 100 < 7 ? algid::Status::kWarmup : algid::Status::kOk));
    if (s == 399)
      for (int i = 0; i < n; ++i)
        worst = std::max(worst, std::abs(est.mass()(i) / truth.m[static_cast<std::size_t>(i)] - 1));
  }
  std::printf("%s after bad sample and reseed at t = 0.1 s: mass error %.2e at t0 + 0.3 s\n", label<Est>(n).c_str(),
              worst);
  CHECK(est.all_valid());
  CHECK(worst < 1e-6);
  CHECK(est.samples() == 300);
  CHECK(std::abs(est.window() - 293 * cfg.dt) < 1e-15);
  est.reseed();
  CHECK(est.samples() == 0 && !est.valid()(0) && !est.all_valid());
  // A finite sample so large that the systems of eq. 5 overflow poisons every later instant of
  // the window: reported as a bad input and reseeded, then the estimator recovers.
  for (int s = 0; s < 100; ++s) est.update(rec.a(s), rec.u(s));
  CHECK(est.all_valid());
  std::vector<double> huge(static_cast<std::size_t>(n), 0.0);
  huge[0] = 1e200;
  est.update(huge.data(), ok.data());
  int reported = -1;  // the sample enters the systems once the quadrature's delay has passed
  for (int s = 100; s < 400; ++s)
    if (est.update(rec.a(s), rec.u(s)) == algid::Status::kBadInput && reported < 0) reported = s - 100;
  CHECK(reported >= 0 && reported <= Est::kDelay + 1);
  CHECK(est.all_valid());
  for (int i = 0; i < n; ++i) CHECK(std::isfinite(est.mass()(i)));
}

// Signals scaled far outside any physical range: valid() is never true for an estimate that
// is not a number.
template <class Est>
void scaled_signals_are_never_valid_nonfinite(int n) {
  const algid_test::SineChainN truth(n, 17);
  typename Est::Config cfg;
  const algid_test::Samples rec(truth, 400, cfg.dt);
  for (double scale : {1e-160, 1e-75, 1e80, 1e150}) {
    Est est(cfg, n);
    std::vector<double> a(static_cast<std::size_t>(n)), u(a);
    long lies = 0;
    for (int s = 0; s < 400; ++s) {
      for (int i = 0; i < n; ++i) {
        a[static_cast<std::size_t>(i)] = rec.a(s)[i] * scale;
        u[static_cast<std::size_t>(i)] = rec.u(s)[i] * scale;
      }
      est.update(a.data(), u.data());
      for (int i = 0; i < n; ++i)
        lies += est.valid()(i) && !(std::isfinite(est.mass()(i)) && std::isfinite(est.damping()(i)));
    }
    CHECK(lies == 0);
  }
}

template <class Est>
void constant_force_is_not_identifiable() {
  // From a constant force since t0 (B = 0) only the ratios are identifiable: eq. 5 is
  // singular and the validity rule must report nothing.
  typename Est::Config cfg;
  cfg.dt = 1e-3;
  Est est(cfg, 1);
  const double m = 2, c = 3, k = 1000, F = 5;
  double x = 0, v = 0;
  for (int s = 0; s < 500; ++s) {
    const double a = (F - c * v - k * x) / m;
    est.update(&a, &F);
    // semi-implicit Euler is enough: the point is that B == 0 exactly
    v += a * cfg.dt;
    x += v * cfg.dt;
  }
  CHECK(!est.valid()(0));
  CHECK(std::isnan(est.mass()(0)));
}

template <class Est>
bool throws(const typename Est::Config& cfg, int n) {
  try {
    Est est(cfg, n);
  } catch (const std::invalid_argument&) {
    return true;
  }
  return false;
}

void configuration_is_validated() {
  using Fixed = algid::ChainEstimator<3>;
  using Dyn = algid::ChainEstimator<Dynamic>;
  Fixed::Config ok, bad_dt, bad_samples, bad_hadamard, tiny_dt, huge_dt;
  bad_dt.dt = -1;
  tiny_dt.dt = 1e-300;  // the time scaling tau^-7 would overflow
  huge_dt.dt = 1e300;
  bad_samples.validity.min_samples = 0;
  bad_hadamard.validity.min_hadamard = 1.0;
  CHECK(Fixed::validate(ok) == algid::ConfigError::kNone);
  CHECK(Fixed::validate(ok, 4) == algid::ConfigError::kBadDofs);  // a fixed size takes N only
  CHECK(Fixed::validate(bad_dt) == algid::ConfigError::kBadSamplePeriod);
  CHECK(Fixed::validate(tiny_dt) == algid::ConfigError::kBadSamplePeriod);
  CHECK(Fixed::validate(huge_dt) == algid::ConfigError::kBadSamplePeriod);
  CHECK(Dyn::validate(ok, 7) == algid::ConfigError::kNone);
  CHECK(Dyn::validate(ok, 0) == algid::ConfigError::kBadDofs);
  CHECK(Dyn::validate(ok, -3) == algid::ConfigError::kBadDofs);
  CHECK(Dyn::validate(bad_dt, 3) == algid::ConfigError::kBadSamplePeriod);
  CHECK(Dyn::validate(bad_samples, 3) == algid::ConfigError::kBadMinSamples);
  CHECK(Dyn::validate(bad_hadamard, 3) == algid::ConfigError::kBadMinHadamard);
  CHECK(algid::validate(ok, 0) == algid::ConfigError::kBadDofs);
  CHECK(throws<Fixed>(bad_dt, 3));
  CHECK(throws<Fixed>(ok, 4));
  CHECK(!throws<Fixed>(ok, 3));
  CHECK(throws<Dyn>(ok, 0));
  CHECK(throws<Dyn>(bad_dt, 5));
  CHECK(throws<Dyn>(bad_samples, 5));
  CHECK(!throws<Dyn>(ok, 1));
  CHECK(std::string(algid::to_string(algid::ConfigError::kBadDofs)).find("DOF") != std::string::npos);
  // Sizes and constants.
  static_assert(algid::ChainEstimator<3>::kDelay == 6, "P = 8 lags 6 samples");
  static_assert(Dyn::kDelay == 6 && Dyn::kDofs == Dynamic && Dyn::kRegisters == Dynamic, "run-time size");
  static_assert(Dyn::kLanes == algid::detail::lane_width<(1 << 30), double>(), "the widest lanes for Dynamic");
  static_assert(algid::ChainEstimator<1>::kSystem == 3 && Dyn::kSystem == 4 && algid::ChainEstimator<2>::kSystem == 4,
                "3x3 systems for one DOF");
  Dyn d(ok, 30);
  CHECK(d.dofs() == 30 && d.samples() == 0 && d.window() == 0.0 && d.config().dt == ok.dt);
  CHECK(d.mass().size() == 30 && d.damping().size() == 30 && d.stiffness().size() == 31 && d.valid().size() == 30);
  CHECK(d.mass().array().isNaN().all() && !d.valid().any());
}

}  // namespace

int main() {
  // The oracle, every size.
  oracle_fixed<1>(101);
  oracle_fixed<2>(102);
  oracle_fixed<3>(103);
  oracle_fixed<5>(105);
  oracle_fixed<11>(111);
  for (int n : {1, 2, 3, 5, 11, 30}) oracle_dynamic(n, 200u + static_cast<unsigned>(n));
  std::printf(
      "oracle, every case: theta_instant |rel| * hadamard %.2e, rel %.2e (hadamard > 1e-2), %.2e (> 1e-6); "
      "hadamard %.2e; eq. 7 from t0 + 100 ms %.2e (3x3 DOF %.2e), from t0 + 30 ms %.2e; %ld mismatches; "
      "vs long double: |rel| * hadamard %.2e (double LU oracle %.2e)\n",
      g_oracle.instant_scaled, g_oracle.instant_1e2, g_oracle.instant_1e6, g_oracle.hadamard, g_oracle.eq7,
      g_oracle.eq7_reduced, g_oracle.eq7_early, g_oracle.mismatches, g_oracle.accuracy, g_oracle.accuracy_oracle);
  model_mismatch_weighting();
  // Exactness.
  exact_both<1>(1, algid::Boundary::kFixed);
  exact_both<1>(2, algid::Boundary::kFree);
  exact_both<2>(3, algid::Boundary::kFixed);
  exact_both<3>(4, algid::Boundary::kFixed);
  exact_both<3>(5, algid::Boundary::kFree);
  exact_both<5>(6, algid::Boundary::kFixed);
  exact_both<10>(10, algid::Boundary::kFree);
  exact_case<algid::ChainEstimator<Dynamic>>(11, 12, algid::Boundary::kFixed);
  exact_case<algid::ChainEstimator<Dynamic>>(11, 13, algid::Boundary::kFree);
  exact_case<algid::ChainEstimator<Dynamic>>(30, 14, algid::Boundary::kFixed);
  exact_case<algid::ChainEstimator<Dynamic>>(30, 15, algid::Boundary::kFree);
  // Multisine accuracy.
  multisine_case<algid::ChainEstimator<1>>(1, 7);
  multisine_case<algid::ChainEstimator<3>>(3, 8);
  multisine_case<algid::ChainEstimator<10>>(10, 9);
  multisine_case<algid::ChainEstimator<2>>(2, 12);
  for (int n : {1, 2, 3, 10, 11, 30}) multisine_case<algid::ChainEstimator<Dynamic>>(n, 20u + static_cast<unsigned>(n));
  bad_samples_and_reseed<algid::ChainEstimator<3>>(3);
  bad_samples_and_reseed<algid::ChainEstimator<Dynamic>>(3);
  bad_samples_and_reseed<algid::ChainEstimator<Dynamic>>(11);
  scaled_signals_are_never_valid_nonfinite<algid::ChainEstimator<3>>(3);
  scaled_signals_are_never_valid_nonfinite<algid::ChainEstimator<Dynamic>>(11);
  constant_force_is_not_identifiable<algid::ChainEstimator<1>>();
  constant_force_is_not_identifiable<algid::ChainEstimator<Dynamic>>();
  configuration_is_validated();
  return algid_test::finish("test_estimator");
}
