// ContinuousEstimator: the firmware contract (no allocation in update()/reset(), noexcept; the
// guards' negative controls), fixed N and N = Dynamic, weak-form and algebraic windows;
// ContinuousEstimator<Dynamic>(config, 3) equal to ContinuousEstimator<3> to the bit over a
// record with a step change; the algebraic window schedule against a hand-reseeded
// ChainEstimator, the aggregation against an independent median / block-median computation;
// weak-form windows exact on closed-form signals; tracking of a 20 % stiffness step, and no
// alarm on a constant system under 40 dB noise. (The weak-form rows against a numpy oracle:
// tests/test_weak_form.py.)
#include "alloc_guard.hpp"  // first: before any Eigen header

#include <algid/algid.hpp>

#include "check.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <random>
#include <type_traits>
#include <vector>

namespace {

using algid_test::NoAllocationScope;

constexpr double kDt = 1e-3;

// Prescribed trajectories x_i(t) = sum_q A_iq sin(w_q t + phi_iq) with 8 tones log-spaced over
// 1-20 Hz and displacement amplitudes falling as 1/w (a forced chain's response is dominated
// by its low modes), forces from eq. 1 in closed form; parameters drawn around Table 1. The
// closed_form.hpp SineChain has equal displacement amplitudes up to 23 Hz: its accelerations
// are dominated by the top tone and barely inform the springs under noise.
template <int N>
struct ToneChain {
  std::array<double, N> m{}, c{};
  std::array<double, N + 1> k{};
  static constexpr int kTones = 8;
  std::array<double, kTones> w{};
  std::array<std::array<double, kTones>, N> amp{}, phase{};

  explicit ToneChain(unsigned seed) {
    std::mt19937 gen(seed);
    auto uni = [&gen](double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(gen()) / 4294967296.0); };
    for (int i = 0; i < N; ++i) {
      m[static_cast<std::size_t>(i)] = 2.0 * uni(0.5, 1.5);
      c[static_cast<std::size_t>(i)] = 5.0 * uni(0.5, 1.5);
    }
    for (auto& kk : k) kk = 900.0 * uni(0.5, 1.5);
    for (int q = 0; q < kTones; ++q)
      w[static_cast<std::size_t>(q)] = 2 * 3.141592653589793 * std::pow(20.0, (q + uni(0.0, 1.0)) / kTones);
    for (auto& row : amp)
      for (int q = 0; q < kTones; ++q)
        row[static_cast<std::size_t>(q)] = 1e-3 * w[0] / w[static_cast<std::size_t>(q)] * uni(0.5, 1.5);
    for (auto& row : phase)
      for (auto& p : row) p = uni(0.0, 6.283185307179586);
  }
  double deriv(int i, int order, double t) const {
    if (i < 0 || i >= N) return 0.0;
    double v = 0;
    for (int q = 0; q < kTones; ++q) {
      const std::size_t a = static_cast<std::size_t>(i), b = static_cast<std::size_t>(q);
      v += amp[a][b] * std::pow(w[b], order) * std::sin(w[b] * t + phase[a][b] + order * 1.5707963267948966);
    }
    return v;
  }
  double accel(int i, double t) const { return deriv(i, 2, t); }
  double force(int i, double t) const {
    const std::size_t a = static_cast<std::size_t>(i);
    return m[a] * deriv(i, 2, t) + c[a] * deriv(i, 1, t) + k[a] * (deriv(i, 0, t) - deriv(i - 1, 0, t)) +
           k[a + 1] * (deriv(i, 0, t) - deriv(i + 1, 0, t));
  }
};

// A recorded run of a ToneChain (prescribed trajectories, forces from eq. 1) whose springs can
// step at a given time: exact closed-form signals, optionally with white noise of a given SNR
// on accelerations and forces. Gaussian noise from mt19937 by Box-Muller, so the record is the
// same with every standard library.
template <int N>
struct Record {
  std::vector<double> accel, force;  // T x N, row-major
  ToneChain<N> before, after;
  long step_sample = -1;
  long T = 0;

  Record(unsigned seed, long samples, long step_at, int spring, double factor, double snr_db)
      : before(seed), after(seed), step_sample(step_at), T(samples) {
    after.k[static_cast<std::size_t>(spring)] *= factor;
    accel.resize(static_cast<std::size_t>(T * N));
    force.resize(static_cast<std::size_t>(T * N));
    for (long s = 0; s < T; ++s) {
      const auto& chain = (step_at >= 0 && s >= step_at) ? after : before;
      for (int i = 0; i < N; ++i) {
        accel[static_cast<std::size_t>(s * N + i)] = chain.accel(i, static_cast<double>(s) * kDt);
        force[static_cast<std::size_t>(s * N + i)] = chain.force(i, static_cast<double>(s) * kDt);
      }
    }
    if (snr_db > 0) add_noise(seed + 1000u, std::pow(10.0, -snr_db / 20.0));
  }

  void add_noise(unsigned seed, double ratio) {
    std::mt19937 gen(seed);
    auto uniform = [&gen]() { return (static_cast<double>(gen()) + 0.5) / 4294967296.0; };
    auto gauss = [&]() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(6.283185307179586 * uniform()); };
    for (auto* signal : {&accel, &force}) {
      for (int i = 0; i < N; ++i) {
        double ss = 0;
        for (long s = 0; s < T; ++s)
          ss += (*signal)[static_cast<std::size_t>(s * N + i)] * (*signal)[static_cast<std::size_t>(s * N + i)];
        const double sigma = ratio * std::sqrt(ss / static_cast<double>(T));
        for (long s = 0; s < T; ++s) (*signal)[static_cast<std::size_t>(s * N + i)] += sigma * gauss();
      }
    }
  }
  const double* a(long s) const { return accel.data() + s * N; }
  const double* u(long s) const { return force.data() + s * N; }
  // True parameters m, c, k at sample s.
  std::vector<double> truth(long s) const {
    const auto& c = (step_sample >= 0 && s >= step_sample) ? after : before;
    std::vector<double> p;
    for (int i = 0; i < N; ++i) p.push_back(c.m[static_cast<std::size_t>(i)]);
    for (int i = 0; i < N; ++i) p.push_back(c.c[static_cast<std::size_t>(i)]);
    for (int j = 0; j <= N; ++j) p.push_back(c.k[static_cast<std::size_t>(j)]);
    return p;
  }
};

// update() and reset() under the guard, for ContinuousEstimator<N> and (kDynamic)
// ContinuousEstimator<Dynamic>(config, N), whose construction allocates.
template <int N, class Scalar, bool kDynamic = false, bool kAlgebraic = false>
void no_allocation_in_hot_path() {
  using Est = std::conditional_t<kAlgebraic, algid::AlgebraicContinuousEstimator<kDynamic ? algid::Dynamic : N, Scalar>,
                                 algid::WeakFormContinuousEstimator<kDynamic ? algid::Dynamic : N, Scalar>>;
  typename Est::Config cfg;
  cfg.dt = Scalar(kDt);
  auto est = std::make_unique<Est>(cfg, N);  // configuration phase: may allocate
  static_assert(noexcept(est->update(std::declval<const Scalar*>(), std::declval<const Scalar*>())), "update noexcept");
  static_assert(noexcept(est->reset()), "reset noexcept");
  if constexpr (!kDynamic) {
    static_assert(noexcept(est->update(std::declval<const algid::Vector<Scalar, N>&>(),
                                       std::declval<const algid::Vector<Scalar, N>&>())),
                  "update noexcept");
  }
  // A closed-form 20 % step of spring 1 at 6 s: exercises warm-up, blocks, the step test,
  // the restart and (at 9 s) the bad-sample path, all inside the guard.
  const Record<N> rec(5, 12000, 6000, 1, 0.8, 0.0);
  std::vector<Scalar> accel(rec.accel.begin(), rec.accel.end()), force(rec.force.begin(), rec.force.end());
  accel[9000 * N] = Scalar(NAN);
  bool threw = false;
  long allocations = -1;
  long events = 0;
  try {
    NoAllocationScope scope;
    for (long s = 0; s < rec.T; ++s) {
      est->update(accel.data() + s * N, force.data() + s * N);
      events += est->events();
      volatile Scalar sink = est->estimate()(0) + est->sigma()(N) + est->mass()(0) + est->stiffness()(N);
      (void)sink;
    }
    est->reset();
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  std::printf("  %s N=%d %s %s: %ld allocations in update()/reset(), %ld events\n", kDynamic ? "Dynamic" : "fixed", N,
              sizeof(Scalar) == 4 ? "float" : "double", kAlgebraic ? "algebraic" : "weak form", allocations, events);
  CHECK(!threw);
  CHECK(allocations == 0);
  CHECK(events >= 1);  // the restart path did run under the guard
}

// ContinuousEstimator<Dynamic>(config, 3) and ContinuousEstimator<3> on a record with a 20 %
// step of k_2 (40 dB noise, a bad sample, default configuration: prefilter, detector,
// amortized aggregation): the same bits after every sample, in every output (statuses,
// estimates, sigmas, window results, events and their contents, per-parameter tracks).
void dynamic_equals_fixed() {
  constexpr int N = 3;
  using Fixed = algid::WeakFormContinuousEstimator<N>;
  using Dyn = algid::WeakFormContinuousEstimator<algid::Dynamic>;
  const auto same = [](double a, double b) {
    return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof(double)) == 0;
  };
  Record<N> rec(31, 10000, 6000, 1, 0.8, 40.0);
  rec.accel[static_cast<std::size_t>(4321 * N + 1)] = NAN;
  auto fixed = std::make_unique<Fixed>(Fixed::Config{});
  auto dyn = std::make_unique<Dyn>(Dyn::Config{}, N);
  CHECK(dyn->dofs() == N && dyn->params() == Fixed::kParams && dyn->estimate().size() == Fixed::kParams);
  long differences = 0, events = 0, step_events = 0;
  for (long s = 0; s < rec.T; ++s) {
    differences += fixed->update(rec.a(s), rec.u(s)) != dyn->update(rec.a(s), rec.u(s));
    differences += fixed->ready() != dyn->ready() || fixed->samples() != dyn->samples();
    differences += fixed->window_results() != dyn->window_results() || fixed->total_events() != dyn->total_events();
    for (int j = 0; j < Fixed::kParams; ++j) {
      differences += !same(fixed->estimate()(j), dyn->estimate()(j)) + !same(fixed->sigma()(j), dyn->sigma()(j));
      differences += !same(fixed->last_window()(j), dyn->last_window()(j));
      differences += !same(fixed->window_spread(j), dyn->window_spread(j)) +
                     (fixed->since_restart(j) != dyn->since_restart(j));
    }
    for (int i = 0; i < N; ++i)
      differences += !same(fixed->mass()(i), dyn->mass()(i)) + !same(fixed->damping()(i), dyn->damping()(i));
    for (int j = 0; j <= N; ++j) differences += !same(fixed->stiffness()(j), dyn->stiffness()(j));
    differences += fixed->events() != dyn->events();
    for (int e = 0; e < std::min(fixed->events(), dyn->events()); ++e) {
      const auto &a = fixed->event(e), &b = dyn->event(e);
      differences += a.sample != b.sample || a.param != b.param || a.kind != b.kind || !same(a.before, b.before) ||
                     !same(a.after, b.after);
      ++events;
      step_events += a.kind == algid::ChangeKind::kStep && a.param == 2 * N + 1 && s >= 6000;
    }
  }
  std::printf(
      "  Dynamic n=3 against ContinuousEstimator<3>, 10 s with a 20 %% step at 6 s and a bad sample: %ld differing "
      "values, %ld events (%ld step events on k_2 after the step), %ld window results\n",
      differences, events, step_events, fixed->window_results());
  CHECK(differences == 0);
  CHECK(step_events >= 1);
  CHECK(fixed->window_results() > 70);  // 0.5 s weak-form windows, one every 125 ms
}

void configuration_is_validated() {
  using Est = algid::WeakFormContinuousEstimator<3>;
  auto rejected = [](auto mutate, algid::ContinuousConfigError expect) {
    Est::Config c;
    mutate(c);
    CHECK(Est::validate(c) == expect);
    bool threw = false;
    try {
      Est e(c);
    } catch (const std::invalid_argument&) {
      threw = true;
    }
    CHECK(threw);
  };
  using E = algid::ContinuousConfigError;
  rejected([](Est::Config& c) { c.dt = 0; }, E::kBadSamplePeriod);
  rejected([](Est::Config& c) { c.window_s = 0.01; }, E::kBadWindow);  // 10 samples < P + 16
  rejected([](Est::Config& c) { c.window_s = NAN; }, E::kBadWindow);
  rejected([](Est::Config& c) { c.window_s = 1e6; }, E::kBadWindow);  // 1e9 samples > 1e7
  rejected([](Est::Config& c) { c.stagger = 5; }, E::kBadStagger);     // MaxStagger = 4
  rejected([](Est::Config& c) { c.block = 65; }, E::kBadBlock);        // Capacity = 64
  rejected([](Est::Config& c) { c.confirm = -1; }, E::kBadConfirm);
  rejected([](Est::Config& c) { c.step_threshold = 0; }, E::kBadThreshold);
  rejected([](Est::Config& c) { c.min_relative_spread = -1; }, E::kBadSpreadFloor);
  rejected([](Est::Config& c) { c.min_windows = 2; }, E::kBadMinWindows);
  rejected([](Est::Config& c) { c.overlap_efficiency = 0; }, E::kBadEfficiency);
  rejected([](Est::Config& c) { c.horizon_s = -1; }, E::kBadHorizon);
  rejected([](Est::Config& c) { c.band_hz = 1; }, E::kBadBand);      // Q = 0.5 harmonics < 2
  rejected([](Est::Config& c) { c.band_hz = 460; }, E::kBadBand);    // >= 0.45 fs
  rejected([](Est::Config& c) { c.accel_noise = -2; }, E::kBadNoise);
  rejected([](Est::Config& c) { c.force_noise = NAN; }, E::kBadNoise);
  rejected([](Est::Config& c) { c.long_window_s = -2; }, E::kBadLongWindow);
  rejected([](Est::Config& c) { c.long_window_s = NAN; }, E::kBadLongWindow);
  rejected([](Est::Config& c) { c.long_window_s = 0.01; }, E::kBadLongWindow);  // 10 samples < 32
  CHECK(Est::validate(Est::Config{}) == E::kNone);
  // The algebraic windows' own fields.
  using Alg = algid::AlgebraicContinuousEstimator<3>;
  auto algebraic_rejected = [](auto mutate, algid::ContinuousConfigError expect) {
    Alg::Config c;
    mutate(c);
    CHECK(Alg::validate(c) == expect);
  };
  algebraic_rejected([](Alg::Config& c) { c.window_s = 0.01; }, E::kBadWindow);  // 10 samples < P + 16
  algebraic_rejected([](Alg::Config& c) { c.validity.min_samples = 0; }, E::kBadMinSamples);
  algebraic_rejected([](Alg::Config& c) { c.prefilter_hz = 450; }, E::kBadPrefilter);  // >= 0.45 fs
  algebraic_rejected([](Alg::Config& c) { c.prefilter_hz = -2; }, E::kBadPrefilter);
  algebraic_rejected([](Alg::Config& c) { c.prefilter_hz = 1e-300; }, E::kBadPrefilter);  // start-up of ~1e300 samples
  algebraic_rejected([](Alg::Config& c) { c.prefilter_hz = 1e-4; }, E::kBadPrefilter);  // below 1e-6 / dt
  algebraic_rejected([](Alg::Config& c) { c.prefilter_order = 3; }, E::kBadPrefilter);
  algebraic_rejected([](Alg::Config& c) { c.overlap_efficiency = 0; }, E::kBadEfficiency);
  CHECK(Alg::validate(Alg::Config{}) == E::kNone);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Window results against hand-reseeded ChainEstimators; running estimate against an
// independent median (before the first block) and mean of block medians (after), with the
// detector off so no restart interferes.
void schedule_and_aggregation_match_oracle() {
  constexpr int N = 3;
  using Est = algid::AlgebraicContinuousEstimator<N>;
  Est::Config cfg;
  cfg.detect = false;
  cfg.amortize = false;  // compare right at the window end
  cfg.prefilter_hz = 0;  // raw samples into the windows (the prefilter is checked against scipy in Python)
  auto est = std::make_unique<Est>(cfg);
  const Record<N> rec(11, 8000, -1, 0, 1.0, 40.0);
  const long M = est->window_samples();
  CHECK(M == 300);
  algid::ChainEstimator<N>::Config wc;
  std::vector<algid::ChainEstimator<N>> oracle(4, algid::ChainEstimator<N>(wc));
  std::vector<std::vector<double>> results(Est::kParams);  // per parameter, in arrival order
  long mismatches = 0, harvests = 0, estimate_checks = 0, estimate_mismatches = 0;
  for (long s = 0; s < rec.T; ++s) {
    const long before = est->window_results();
    est->update(rec.a(s), rec.u(s));
    for (int e = 0; e < 4; ++e) {
      const long offset = M * e / 4;
      if (s < offset) continue;
      if ((s - offset) % M == 0) oracle[static_cast<std::size_t>(e)].reseed();
      oracle[static_cast<std::size_t>(e)].update(rec.a(s), rec.u(s));
      if ((s - offset) % M == M - 1) {
        ++harvests;
        const auto& o = oracle[static_cast<std::size_t>(e)];
        for (int i = 0; i < N; ++i) {
          mismatches += o.mass()(i) != est->last_window()(i);
          mismatches += o.damping()(i) != est->last_window()(N + i);
        }
        for (int j = 0; j <= N; ++j) mismatches += o.stiffness()(j) != est->last_window()(2 * N + j);
      }
    }
    if (est->window_results() == before) continue;
    for (int j = 0; j < Est::kParams; ++j) results[static_cast<std::size_t>(j)].push_back(est->last_window()(j));
    // independent aggregation
    for (int j = 0; j < Est::kParams; ++j) {
      const auto& r = results[static_cast<std::size_t>(j)];
      const std::size_t blocks = r.size() / 16;
      double expect;
      if (blocks == 0) {
        expect = median(r);
      } else {
        double sum = 0;
        for (std::size_t b = 0; b < blocks; ++b)
          sum += median(
              std::vector<double>(r.begin() + static_cast<long>(16 * b), r.begin() + static_cast<long>(16 * b + 16)));
        expect = sum / static_cast<double>(blocks);
      }
      ++estimate_checks;
      if (std::abs(expect - est->estimate()(j)) > 1e-12 * std::abs(expect)) ++estimate_mismatches;
    }
  }
  CHECK(harvests == est->window_results());
  CHECK(harvests > 90);
  CHECK(mismatches == 0);
  CHECK(estimate_checks > 900);
  CHECK(estimate_mismatches == 0);
}

// Relative error of the running estimate against the truth at sample s.
template <int N, class Est>
std::vector<double> rel_errors(const Est& est, const Record<N>& rec, long s) {
  const auto truth = rec.truth(s);
  std::vector<double> e;
  for (int j = 0; j < Est::kParams; ++j)
    e.push_back(std::abs(est.estimate()(j) - truth[static_cast<std::size_t>(j)]) / truth[static_cast<std::size_t>(j)]);
  return e;
}

void constant_system_no_alarm_and_accuracy() {
  constexpr int N = 3;
  using Est = algid::WeakFormContinuousEstimator<N>;
  auto est = std::make_unique<Est>(Est::Config{});
  const Record<N> rec(21, 60000, -1, 0, 1.0, 40.0);
  long events = 0;
  double worst_z = 0;
  for (long s = 0; s < rec.T; ++s) {
    est->update(rec.a(s), rec.u(s));
    events += est->events();
    if (s == 10000 - 1) {
      const auto e = rel_errors<N>(*est, rec, s);
      for (int i = 0; i < N; ++i) {
        CHECK(e[static_cast<std::size_t>(i)] < 0.005);  // masses within 0.5 % at 10 s
        CHECK(e[static_cast<std::size_t>(N + i)] < 0.05);  // dampings: weakly excited by this signal
      }
      for (int j = 0; j <= N; ++j) CHECK(e[static_cast<std::size_t>(2 * N + j)] < 0.005);  // springs
    }
  }
  const auto truth = rec.truth(rec.T - 1);
  for (int j = 0; j < Est::kParams; ++j)
    worst_z = std::max(worst_z, std::abs(est->estimate()(j) - truth[static_cast<std::size_t>(j)]) / est->sigma()(j));
  std::printf("  constant system, 40 dB, 60 s: %ld events, worst |error| / sigma %.2f\n", events, worst_z);
  CHECK(events == 0);
  CHECK(worst_z < 6.0);  // the uncertainty is of the right order (bias not included)
}

void step_is_tracked() {
  constexpr int N = 3;
  using Est = algid::WeakFormContinuousEstimator<N>;
  const int spring = 1;  // k_2
  const int param = 2 * N + spring;  // its index in estimate()
  for (double snr : {0.0, 40.0}) {
    auto est = std::make_unique<Est>(Est::Config{});
    const long step = 20000;
    const Record<N> rec(31, 30000, step, spring, 0.8, snr);
    long first_event = -1, other_events = 0, within = -1;
    for (long s = 0; s < rec.T; ++s) {
      est->update(rec.a(s), rec.u(s));
      for (int i = 0; i < est->events(); ++i) {
        const auto& ev = est->event(i);
        if (ev.param == param && ev.kind == algid::ChangeKind::kStep && first_event < 0 && s >= step) first_event = s;
        if (ev.param != param) ++other_events;
      }
      if (s >= step) {
        const double target = rec.after.k[static_cast<std::size_t>(spring)];
        const bool ok = std::abs(est->estimate()(param) - target) < 0.02 * target;
        if (ok && within < 0) within = s;
        if (!ok) within = -1;  // "within" means: from then on
      }
    }
    std::printf("  20 %% step, SNR %s: event after %.3f s, within 2 %% (for good) after %.3f s, %ld other events\n",
                snr > 0 ? "40 dB" : "none", (first_event - step) * kDt, (within - step) * kDt, other_events);
    CHECK(first_event >= step);
    CHECK(first_event - step < 1000);
    CHECK(within >= step);
    CHECK(within - step < 1000);  // tracked to 2 % in under 1 s
    CHECK(other_events == 0);
    if (snr == 0.0) {
      // noise-free: the new value to the quadrature's accuracy
      CHECK_NEAR(est->estimate()(param), rec.after.k[static_cast<std::size_t>(spring)], 1e-5 * rec.after.k[1]);
    }
  }
}

void free_end_and_single_dof() {
  {
    using Est = algid::WeakFormContinuousEstimator<2>;
    Est::Config c;
    c.boundary = algid::Boundary::kFree;
    Est est(c);
    CHECK(est.estimate()(Est::kParams - 1) == 0.0);
    CHECK(est.sigma()(Est::kParams - 1) == 0.0);
  }
  {
    using Est = algid::WeakFormContinuousEstimator<1>;
    Est est(Est::Config{});
    const Record<1> rec(3, 2000, -1, 0, 1.0, 0.0);
    algid::Status st = algid::Status::kWarmup;
    for (long s = 0; s < rec.T; ++s) st = est.update(rec.a(s), rec.u(s));
    CHECK(st == algid::Status::kOk);
    CHECK(std::isnan(est.estimate()(3)));  // k_2 alone is not identifiable with n = 1
    CHECK_NEAR(est.estimate()(2), rec.before.k[0] + rec.before.k[1], 1e-6 * rec.before.k[0]);
  }
}

void prefilter_keeps_the_model() {
  // Noise-free closed-form record: with the default prefilter (fs/20, order 4) the window
  // results still return the parameters (the same LTI filter on both sides of eq. 1), and
  // windows start after the settle time ln(1e6) / decay.
  constexpr int N = 3;
  using Est = algid::AlgebraicContinuousEstimator<N>;
  Est::Config cfg;
  cfg.amortize = false;
  auto est = std::make_unique<Est>(cfg);
  CHECK_NEAR(est->prefilter_hz(), 50.0, 1e-9);
  CHECK(est->settle_samples() == 115);  // 13.8155 / (2 pi 50 sin(pi/8)) = 0.1149 s
  const Record<N> rec(41, 3000, -1, 0, 1.0, 0.0);
  long first = -1;
  double worst = 0;
  for (long s = 0; s < rec.T; ++s) {
    const long before = est->window_results();
    est->update(rec.a(s), rec.u(s));
    if (est->window_results() == before) continue;
    if (first < 0) first = s;
    const auto truth = rec.truth(s);
    for (int j = 0; j < Est::kParams; ++j)
      worst = std::max(worst, std::abs(est->last_window()(j) / truth[static_cast<std::size_t>(j)] - 1.0));
  }
  std::printf("  prefilter on, noise-free: first window result at sample %ld, worst window error %.2e\n", first, worst);
  CHECK(first == 115 + 300 - 1);
  CHECK(worst < 1e-5);
}

// WeakFormWindows on noise-free closed-form signals (known zero noise, so no bias term and
// the first windows unweighted; with the model set, weighted): every window result returns
// the parameters to the quadrature's accuracy, for a wall and a free end. The sums are the
// integrals to O(dt^4) (the taper and its first three derivatives vanish at the ends).
template <int N>
void weak_form_is_exact(algid::Boundary boundary) {
  using W = algid::WeakFormWindows<N>;
  typename W::Config cfg;
  cfg.boundary = boundary;
  cfg.accel_noise = 1e-9;  // weights need a noise level (its bias term is negligible here)
  cfg.force_noise = 0;
  auto w = std::make_unique<W>(cfg);
  Record<N> rec(51, 4000, -1, 0, 1.0, 0.0);
  if (boundary == algid::Boundary::kFree) {  // no right wall: rebuild the forces without k_{N+1}
    rec.before.k[N] = rec.after.k[N] = 0.0;
    for (long s = 0; s < rec.T; ++s)
      for (int i = 0; i < N; ++i)
        rec.force[static_cast<std::size_t>(s * N + i)] = rec.before.force(i, static_cast<double>(s) * kDt);
  }
  auto truth = rec.truth(0);
  if (N == 1 && boundary == algid::Boundary::kFixed) {  // one DOF between walls: k_1 + k_2 only
    truth[2] += truth[3];
    truth[3] = NAN;
  }
  double worst = 0;
  long results = 0, weighted = 0;
  for (long s = 0; s < rec.T; ++s) {
    if (s == 1000) w->set_model(truth.data());
    if (!w->update(rec.a(s), rec.u(s))) continue;
    ++results;
    weighted += w->result_weighted();
    for (int j = 0; j < 3 * N + 1; ++j) {
      const double t = truth[static_cast<std::size_t>(j)];
      if (std::isnan(t) || t == 0.0) {
        CHECK(std::isnan(t) ? std::isnan(w->result()(j)) : w->result()(j) == 0.0);
        continue;
      }
      worst = std::max(worst, std::abs(w->result()(j) / t - 1.0));
    }
  }
  std::printf("  weak form N=%d %s, noise-free: %ld window results (%ld GLS-weighted), worst relative error %.1e\n", N,
              boundary == algid::Boundary::kFree ? "free end" : "walls", results, weighted, worst);
  // every window that ended latency_samples() before the end of the record (amortized solve)
  CHECK(results == (rec.T - w->latency_samples() - w->window_samples()) / w->hop_samples() + 1);
  CHECK(weighted > 5 && weighted < results);
  CHECK(worst < 1e-5);  // 1e-6 measured: the Riemann sums' O(dt^4 (pi/W)^4) end terms
}

// The weak form's joint solve is spread: a window result joins the joint system on its own
// sample, which is factored on the next and solved (the reported estimates move) on the one
// after, so no sample pays for the window's solve and the joint's together (the window's own
// factorisation and back-substitutions have samples of their own: latency_samples(), checked
// in weak_form_is_exact). One joint sum here (no long windows): the long windows' sum has the
// same schedule on its own window results.
void joint_solve_is_spread() {
  constexpr int N = 3;
  using Est = algid::WeakFormContinuousEstimator<N>;
  Est::Config config;
  config.long_window_s = 0;
  auto est = std::make_unique<Est>(config);
  const Record<N> rec(23, 12000, -1, 0, 1.0, 40.0);
  std::vector<std::array<double, Est::kParams>> history;
  std::vector<long> result_samples;
  long results = 0;
  for (long s = 0; s < rec.T; ++s) {
    est->update(rec.a(s), rec.u(s));
    std::array<double, Est::kParams> e{};
    for (int j = 0; j < Est::kParams; ++j) e[static_cast<std::size_t>(j)] = est->estimate()(j);
    history.push_back(e);
    if (est->window_results() != results) result_samples.push_back(s);
    results = est->window_results();
  }
  int checked = 0, moved = 0;
  for (long s : result_samples) {
    if (s < 5000 || s + 2 >= rec.T) continue;  // the joint in force, every parameter trusted
    const auto &before = history[static_cast<std::size_t>(s - 1)], &at = history[static_cast<std::size_t>(s)],
               &next = history[static_cast<std::size_t>(s + 1)], &after = history[static_cast<std::size_t>(s + 2)];
    for (int j = 0; j < Est::kParams; ++j) {
      const auto u = static_cast<std::size_t>(j);
      CHECK(at[u] == before[u]);
      CHECK(next[u] == before[u]);
      moved += after[u] != before[u];
    }
    ++checked;
  }
  std::printf("  joint solve spread: %d window results checked, %d estimates moved two samples after\n", checked,
              moved);
  CHECK(checked >= 40);
  CHECK(moved >= checked * (Est::kParams - 1));
}

// Long windows (`long_window_s`, default three times window_s): a second weak-form engine with a
// joint sum of its own, each parameter reported from the sum with the smaller variance. Without
// them (0) nothing is reported from a long sum; with them, on a 40 s record at 40 dB, some
// parameters are, each with a sigma no larger than the short sum alone gives it (the short
// sums of the two estimators differ only through the weights' model), and every estimate stays
// within 4 sigma of the truth.
void long_windows_report_where_more_certain() {
  constexpr int N = 3;
  using Est = algid::WeakFormContinuousEstimator<N>;
  Est::Config none;
  none.long_window_s = 0;
  auto both = std::make_unique<Est>(Est::Config{});
  auto short_only = std::make_unique<Est>(none);
  CHECK(short_only->windows().long_windows() == nullptr);
  CHECK(both->windows().long_windows() != nullptr);
  CHECK(both->windows().long_windows()->window_samples() == 3 * both->windows().short_windows().window_samples());
  const Record<N> rec(24, 40000, -1, 0, 1.0, 40.0);
  for (long s = 0; s < rec.T; ++s) {
    both->update(rec.a(s), rec.u(s));
    short_only->update(rec.a(s), rec.u(s));
  }
  const auto truth = rec.truth(rec.T - 1);
  int from_long = 0;
  double worst_z = 0.0, worst_ratio = 0.0;
  for (int j = 0; j < Est::kParams; ++j) {
    CHECK(!short_only->from_long_windows(j));
    if (!both->from_long_windows(j)) continue;
    ++from_long;
    worst_ratio = std::max(worst_ratio, both->sigma()(j) / short_only->sigma()(j));
  }
  for (int j = 0; j < Est::kParams; ++j)
    worst_z = std::max(worst_z, std::abs(both->estimate()(j) - truth[static_cast<std::size_t>(j)]) / both->sigma()(j));
  std::printf(
      "  long windows, 40 dB, 40 s: %d of %d parameters from the long sum, sigma / short-only sigma <= %.2f, "
      "worst |error| / sigma %.2f\n",
      from_long, Est::kParams, worst_ratio, worst_z);
  CHECK(from_long >= 1);
  CHECK(worst_ratio < 1.05);
  CHECK(worst_z < 4.0);
}

// record() against update() sample by sample (both window sources, a step, a bad sample): the
// same statuses, the same estimates and sigmas in every stride-th row, the same window results
// and events, to the bit; and record() allocates nothing of its own.
template <class Est>
void record_equals_update(const char* name) {
  constexpr int N = 3;
  Record<N> rec(17, 8000, 5000, 1, 0.8, 40.0);
  rec.accel[static_cast<std::size_t>(3210 * N)] = NAN;
  const long T = rec.T, stride = 7, rows = (T + stride - 1) / stride;
  auto a = std::make_unique<Est>(typename Est::Config{});
  auto b = std::make_unique<Est>(typename Est::Config{});
  std::vector<std::int8_t> status(static_cast<std::size_t>(T));
  std::vector<double> estimate(static_cast<std::size_t>(rows * Est::kParams)), sigma(estimate.size());
  std::vector<std::int64_t> sample(static_cast<std::size_t>(rows));
  const algid::ContinuousHistories<double> out{status.data(), estimate.data(), sigma.data(), sample.data(), stride};
  struct Log {
    const Est* e;
    long windows = 0, events = 0;
    double window_sum = 0;
    std::vector<typename Est::Event> list;
    void window(long) {
      ++windows;
      for (int j = 0; j < e->params(); ++j)
        if (std::isfinite(e->last_window()(j))) window_sum += e->last_window()(j);
    }
    void event(const typename Est::Event& ev) { list.push_back(ev); }
  } log{b.get(), 0, 0, 0.0, {}};
  log.list.reserve(1000);
  long allocations = -1;
  {
    NoAllocationScope scope;
    b->record(rec.accel.data(), rec.force.data(), T, out, log);
    allocations = scope.allocations();
  }
  long differences = 0, windows = 0;
  double window_sum = 0;
  std::size_t events = 0;
  for (long t = 0; t < T; ++t) {
    const long before = a->window_results();
    differences += static_cast<std::int8_t>(a->update(rec.a(t), rec.u(t))) != status[static_cast<std::size_t>(t)];
    if (a->window_results() != before) {
      ++windows;
      for (int j = 0; j < a->params(); ++j)
        if (std::isfinite(a->last_window()(j))) window_sum += a->last_window()(j);
    }
    for (int e = 0; e < a->events(); ++e, ++events) {
      const auto& x = a->event(e);
      differences += events >= log.list.size() || log.list[events].sample != x.sample ||
                     log.list[events].param != x.param || !(log.list[events].after == x.after);
    }
    if (t % stride != 0) continue;
    const long row = t / stride;
    differences += sample[static_cast<std::size_t>(row)] != t;
    for (int j = 0; j < Est::kParams; ++j) {
      const double e = estimate[static_cast<std::size_t>(row * Est::kParams + j)];
      const double s = sigma[static_cast<std::size_t>(row * Est::kParams + j)];
      differences += !(e == a->estimate()(j) || (std::isnan(e) && std::isnan(a->estimate()(j))));
      differences += !(s == a->sigma()(j) || (std::isnan(s) && std::isnan(a->sigma()(j))));
    }
  }
  differences += windows != log.windows || !(window_sum == log.window_sum) || events != log.list.size();
  std::printf("  record() of %s against update(): %ld differing values, %ld windows, %zu events, %ld allocations\n",
              name, differences, windows, events, allocations);
  CHECK(differences == 0);
  CHECK(windows > 40);
  CHECK(events >= 1);
  CHECK(allocations == 0);
}

}  // namespace

// The dropout rules on hand-made channels (detail/dropout.hpp): a channel that never moved is
// not stuck; a repeat shorter than the rule is not a dropout; a frozen channel is stuck from the
// sample that completes the run until it moves; a repeat at the running extreme is clipped.
template <int Channels>
void dropout_rules() {
  algid::detail::DropoutDetector<double, Channels> d;
  d.configure(2, 4, 3);
  int ch = 0;
  const double rest[2] = {0.0, 0.0};
  for (int k = 0; k < 10; ++k) CHECK(d.check(rest, ch) == algid::Dropout::kNone);  // never moved
  const double seq[][2] = {{1.0, 0.5}, {2.0, -0.5}, {1.5, 0.2}, {1.5, 0.1}, {1.5, 0.3}};
  for (const auto& x : seq) CHECK(d.check(x, ch) == algid::Dropout::kNone);  // 1.5 three times: not yet
  const double frozen[2] = {1.5, 0.4};
  CHECK(d.check(frozen, ch) == algid::Dropout::kStuck && ch == 0);  // the fourth 1.5
  const double moving[2] = {1.6, 0.45};
  CHECK(d.check(moving, ch) == algid::Dropout::kNone && ch == -1);
  const double top[2] = {1.55, 0.5};  // channel 1 at its largest value so far
  CHECK(d.check(top, ch) == algid::Dropout::kNone);
  CHECK(d.check(top, ch) == algid::Dropout::kNone);
  CHECK(d.check(top, ch) == algid::Dropout::kClipped && ch == 1);
  d.reset();
  for (int k = 0; k < 10; ++k) CHECK(d.check(top, ch) == algid::Dropout::kNone);  // forgotten: never moved
}

int main() {
  algid_test::guards_fire();
  no_allocation_in_hot_path<1, double>();
  no_allocation_in_hot_path<3, double>();
  no_allocation_in_hot_path<10, double>();
  no_allocation_in_hot_path<3, float>();
  no_allocation_in_hot_path<1, double, true>();  // (n = 10 and float: test_realtime)
  no_allocation_in_hot_path<3, double, true>();
  no_allocation_in_hot_path<3, double, false, true>();
  no_allocation_in_hot_path<3, double, true, true>();
  weak_form_is_exact<3>(algid::Boundary::kFixed);
  weak_form_is_exact<2>(algid::Boundary::kFree);
  weak_form_is_exact<1>(algid::Boundary::kFixed);
  dynamic_equals_fixed();
  configuration_is_validated();
  schedule_and_aggregation_match_oracle();
  constant_system_no_alarm_and_accuracy();
  step_is_tracked();
  joint_solve_is_spread();
  long_windows_report_where_more_certain();
  free_end_and_single_dof();
  prefilter_keeps_the_model();
  dropout_rules<2>();
  dropout_rules<algid::Dynamic>();
  record_equals_update<algid::WeakFormContinuousEstimator<3>>("the weak form");
  record_equals_update<algid::AlgebraicContinuousEstimator<3>>("algebraic windows");
  return algid_test::finish("test_continuous");
}
