// Fuzz harness: both estimators fed closed-form chain records interrupted by random bursts of
// hostile doubles (NaN, inf, DBL_MAX, 1e200-1e300, denormals, zeros, moderate outliers), from a
// fixed seed so that a failure reproduces. Properties checked after every sample and after
// every burst:
//   - valid() is never true for an estimate that is not a number;
//   - a burst of non-finite or overflowing values reseeds by itself: once clean samples
//     resume, the estimates return to the truth (no state stays NaN or frozen);
//   - a burst of finite values is contaminating but harmless: after reseed() the estimates
//     return to the truth;
//   - the continuous estimator, after any burst, is ready again with finite estimates near the
//     truth once clean samples have flowed for a while.
// Built and run in the Release and in the sanitizer builds (tests/test_cpp.py), so every path
// these bursts reach runs under AddressSanitizer and UndefinedBehaviorSanitizer too.
#include <algid/algid.hpp>

#include "check.hpp"
#include "closed_form.hpp"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace {

using algid::Dynamic;
constexpr double kDt = 1e-3;

// Values that must reseed the estimator (non-finite, or so large that eq. 5 overflows).
double poison(std::mt19937& gen) {
  const double menu[] = {std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::infinity(),
                         -std::numeric_limits<double>::infinity(),
                         DBL_MAX,
                         -DBL_MAX,
                         1e300,
                         -1e250,
                         1e200};
  return menu[gen() % (sizeof(menu) / sizeof(menu[0]))];
}

// Finite values that contaminate a window without overflowing it.
double garbage(std::mt19937& gen) {
  const double menu[] = {0.0, -0.0, 4.9e-324, 1e-310, -2.2e-308, 1e-300, 1e5, -3e7, 42.0};
  return menu[gen() % (sizeof(menu) / sizeof(menu[0]))];
}

// Feed samples s0 .. s0 + count of `rec`, checking that valid() never flags a non-number.
template <class Est>
long feed_clean(Est& est, const algid_test::Samples& rec, long s0, long count) {
  long lies = 0;
  for (long s = s0; s < s0 + count; ++s) {
    est.update(rec.a(s), rec.u(s));
    for (int i = 0; i < est.dofs(); ++i) lies += est.valid()(i) && !std::isfinite(est.mass()(i));
  }
  return lies;
}

template <class Est>
long feed_burst(Est& est, int n, std::mt19937& gen, bool poisonous) {
  std::vector<double> a(static_cast<std::size_t>(n)), u(a);
  const int length = 1 + static_cast<int>(gen() % 40);
  long lies = 0;
  for (int s = 0; s < length; ++s) {
    for (int i = 0; i < n; ++i) {
      a[static_cast<std::size_t>(i)] = (gen() % 2) ? (poisonous ? poison(gen) : garbage(gen)) : 1e-3;
      u[static_cast<std::size_t>(i)] = (gen() % 2) ? (poisonous ? poison(gen) : garbage(gen)) : 1e-3;
    }
    if (poisonous) a[gen() % static_cast<std::size_t>(n)] = poison(gen);  // at least one per sample
    est.update(a.data(), u.data());
    for (int i = 0; i < n; ++i) lies += est.valid()(i) && !std::isfinite(est.mass()(i));
  }
  return lies;
}

template <class Est>
double worst_mass_error(const Est& est, const algid_test::SineChainN& truth) {
  double worst = 0;
  for (int i = 0; i < truth.n; ++i) {
    const double e = std::abs(est.mass()(i) / truth.m[static_cast<std::size_t>(i)] - 1);
    worst = std::isfinite(e) ? std::max(worst, e) : std::numeric_limits<double>::infinity();
  }
  return worst;
}

// ChainEstimator: `rounds` bursts, alternately poisonous (recovers alone) and finite
// (recovers after reseed()), each followed by 400 clean samples from a random instant.
template <class Est>
void chain_rounds(int n, unsigned seed, int rounds) {
  const algid_test::SineChainN truth(n, seed);
  const algid_test::Samples rec(truth, 5000, kDt);
  std::mt19937 gen(seed);
  typename Est::Config cfg;
  Est est(cfg, n);
  long lies = 0, stuck = 0;
  double worst = 0;
  for (int r = 0; r < rounds; ++r) {
    const bool poisonous = r % 2 == 0;
    lies += feed_burst(est, n, gen, poisonous);
    if (!poisonous) est.reseed();
    const long s0 = static_cast<long>(gen() % 4500);
    lies += feed_clean(est, rec, s0, 400);
    const double e = worst_mass_error(est, truth);
    stuck += !(est.all_valid() && e < 1e-5);
    worst = std::max(worst, e);
  }
  std::printf(
      "ChainEstimator n = %d, %d bursts: %ld invalid-but-flagged-valid, %ld rounds not recovered, worst "
      "mass error after recovery %.2e\n",
      n, rounds, lies, stuck, worst);
  CHECK(lies == 0);
  CHECK(stuck == 0);
}

// ContinuousEstimator: bursts of every kind, each followed by 6 s of clean samples; after each
// the estimator is ready with every estimate finite and the masses within 1 %.
template <class Est>
void continuous_rounds(int n, unsigned seed, int rounds) {
  const algid_test::SineChainN truth(n, seed);
  const long clean = 6000;
  const algid_test::Samples rec(truth, clean * 2, kDt);
  std::mt19937 gen(seed);
  typename Est::Config cfg;
  auto est = std::make_unique<Est>(cfg, n);
  long stuck = 0;
  double worst = 0;
  for (int r = 0; r < rounds; ++r) {
    std::vector<double> a(static_cast<std::size_t>(n)), u(a);
    const bool poisonous = r % 2 == 0;
    const int length = 1 + static_cast<int>(gen() % 40);
    for (int s = 0; s < length; ++s) {
      for (int i = 0; i < n; ++i) {
        a[static_cast<std::size_t>(i)] = poisonous ? poison(gen) : garbage(gen);
        u[static_cast<std::size_t>(i)] = poisonous ? poison(gen) : garbage(gen);
      }
      est->update(a.data(), u.data());
    }
    const long s0 = static_cast<long>(gen() % static_cast<unsigned>(clean));
    for (long s = s0; s < s0 + clean; ++s) est->update(rec.a(s), rec.u(s));
    bool finite = true;
    for (int j = 0; j < est->params(); ++j) {
      const double v = est->estimate()(j);
      finite &= (n == 1 && j == est->params() - 1) ? std::isnan(v) : std::isfinite(v);  // k_2 of one DOF: NaN
    }
    const double e = worst_mass_error(*est, truth);
    if (!(est->ready() && finite && e < 1e-2))
      std::printf("  round %d (%s): ready %d finite %d error %.3g\n", r, poisonous ? "poison" : "finite", est->ready(),
                  finite, e);
    stuck += !(est->ready() && finite && e < 1e-2);
    worst = std::max(worst, e);
  }
  std::printf("ContinuousEstimator n = %d, %d bursts: %ld rounds not recovered, worst mass error %.2e\n", n, rounds,
              stuck, worst);
  CHECK(stuck == 0);
}

// The outlier guard: once a window has set the scales, one sample 1e12 times the RMS is bad
// input; a channel that was quiet for a window and then moves 1e10 times more is a new level,
// relearnt after one window of rejected samples (never a dead estimator).
void outlier_guard() {
  using Est = algid::WeakFormContinuousEstimator<2>;
  const algid_test::SineChainN truth(2, 9);
  const algid_test::Samples rec(truth, 8000, kDt);
  auto est = std::make_unique<Est>(Est::Config{});
  for (long s = 0; s < 1000; ++s) est->update(rec.a(s), rec.u(s));
  const double spike[2] = {rec.a(1000)[0] * 1e12, rec.a(1000)[1]};
  CHECK(est->update(spike, rec.u(1000)) == algid::Status::kBadInput);
  CHECK(est->update(rec.a(1001), rec.u(1001)) != algid::Status::kBadInput);

  auto quiet = std::make_unique<Est>(Est::Config{});
  double a[2], u[2];
  for (long s = 0; s < 1000; ++s) {
    for (int i = 0; i < 2; ++i) {
      a[i] = rec.a(s)[i] * 1e-10;
      u[i] = rec.u(s)[i] * 1e-10;
    }
    quiet->update(a, u);
  }
  long rejected = 0;
  for (long s = 1000; s < 8000; ++s) rejected += quiet->update(rec.a(s), rec.u(s)) == algid::Status::kBadInput;
  std::printf(
      "outlier guard: a quiet channel that starts to move: %ld samples rejected before relearning, mass "
      "error %.2e at the end\n",
      rejected, worst_mass_error(*quiet, truth));
  CHECK(rejected == quiet->window_samples() - 1);
  CHECK(quiet->ready() && worst_mass_error(*quiet, truth) < 1e-6);
}

}  // namespace

int main() {
  outlier_guard();
  chain_rounds<algid::ChainEstimator<3>>(3, 1, 60);
  chain_rounds<algid::ChainEstimator<1>>(1, 2, 60);
  chain_rounds<algid::ChainEstimator<Dynamic>>(5, 3, 40);
  chain_rounds<algid::ChainEstimator<Dynamic>>(11, 4, 20);
  continuous_rounds<algid::WeakFormContinuousEstimator<3>>(3, 5, 8);
  continuous_rounds<algid::WeakFormContinuousEstimator<Dynamic>>(2, 6, 6);
  return algid_test::finish("test_fuzz");
}
