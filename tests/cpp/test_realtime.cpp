// The firmware contract, proved: after construction, update(), reseed(), run(), record() and the
// accessors of ChainEstimator never allocate, for a fixed N and for N = Dynamic (whose
// construction allocates everything once), and neither do update() and reset() of
// ContinuousEstimator<Dynamic>; all are noexcept. The guards: Eigen's runtime malloc check with a
// throwing eigen_assert, plus a counting global operator new (plain and aligned). Negative
// controls show that both fire. A fixed-size estimator's construction allocates nothing either.
#include "alloc_guard.hpp"  // first: before any Eigen header

#include <algid/algid.hpp>

#include "check.hpp"
#include "closed_form.hpp"

#include <Eigen/Dense>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <new>
#include <vector>

namespace {

using algid::Dynamic;
using algid_test::NoAllocationScope;

// A record of T samples as Scalar (allocated outside the guarded scopes).
template <class Scalar>
struct Record {
  int n;
  long T;
  std::vector<Scalar> accel, force;
  // one_force: the force on DOF 1 only (OneForceChainN, 0.3 s at 10 kHz: its polynomials are
  // well-conditioned near t = 0 only): the homogeneous systems and the scale carried along the
  // chain run in every sample
  Record(int dofs, long samples, unsigned seed, bool one_force = false) : n(dofs), T(samples) {
    const algid_test::Samples s = one_force
                                      ? algid_test::Samples(algid_test::OneForceChainN(dofs, 0, seed), samples, 1e-4)
                                      : algid_test::Samples(algid_test::SineChainN(dofs, seed), samples, 1e-3);
    accel.assign(s.accel.begin(), s.accel.end());
    force.assign(s.force.begin(), s.force.end());
  }
  const Scalar* a(long t) const { return accel.data() + t * n; }
  const Scalar* u(long t) const { return force.data() + t * n; }
};

template <class Est>
const char* label() {
  return Est::kDofs == Dynamic ? "Dynamic" : "fixed";
}

// update() and reseed() sample by sample, the bad-sample path and every accessor, under the guard.
template <class Est, class Scalar>
void no_allocation_in_hot_path(int n, bool one_force = false) {
  typename Est::Config cfg;
  cfg.dt = Scalar(one_force ? 1e-4 : 1e-3);
  if (one_force) cfg.validity.min_hadamard = Scalar(1e-12);  // polynomial trajectories are poorly conditioned
  long constructed = -1;
  std::unique_ptr<Est> owner;
  {
    algid_test::NoAllocationScope counting;  // construction may allocate: counted, not forbidden
    Eigen::internal::set_is_malloc_allowed(true);
    owner = std::make_unique<Est>(cfg, n);
    constructed = counting.allocations() - 1;  // the make_unique itself
  }
  Est& est = *owner;
  static_assert(noexcept(est.update(std::declval<const Scalar*>(), std::declval<const Scalar*>())), "update noexcept");
  static_assert(noexcept(est.reseed()), "reseed noexcept");
  static_assert(noexcept(est.mass()) && noexcept(est.stiffness()) && noexcept(est.valid()) && noexcept(est.theta(0)) &&
                    noexcept(est.theta_instant(0)) && noexcept(est.hadamard(0)) && noexcept(est.all_valid()) &&
                    noexcept(est.forced(0)),
                "accessors noexcept");
  Record<Scalar> rec(n, 3000, 3, one_force);
  rec.accel[static_cast<std::size_t>(2000 * n)] = Scalar(NAN);  // the bad-sample path too
  bool threw = false;
  long allocations = -1;
  try {
    NoAllocationScope scope;
    for (long s = 0; s < rec.T; ++s) {
      if (s == 1000) est.reseed();
      est.update(rec.a(s), rec.u(s));
      volatile Scalar sink = est.mass()(0) + est.damping()(n - 1) + est.stiffness()(n) + est.theta(0)(1) +
                             est.theta_instant(n - 1)(0) + est.hadamard(0) + est.window();
      volatile bool flags = est.valid()(n - 1) && est.all_valid() && est.instant_valid(0) && est.valid().all();
      (void)sink;
      (void)flags;
    }
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  std::printf("%s n=%d %s%s: construction %ld allocations; update()/reseed()/accessors over %ld samples: %ld\n",
              label<Est>(), n, sizeof(Scalar) == 4 ? "float" : "double", one_force ? " one force" : "", constructed,
              rec.T, allocations);
  CHECK(!threw);
  CHECK(allocations == 0);
  CHECK(est.all_valid());
  if (Est::kDofs != Dynamic) CHECK(constructed == 0);  // fixed size: no heap at all
  if (Est::kDofs == Dynamic) CHECK(constructed > 0);
}

// The batch paths: run() and record() over a whole record (with a bad sample) and a reseed()
// between them allocate nothing either.
template <class Est, class Scalar>
void run_does_not_allocate(int n) {
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  Est est(cfg, n), recorder(cfg, n);
  const long T = 1500;
  Record<Scalar> rec(n, T, 4);
  rec.accel[static_cast<std::size_t>(700 * n)] = Scalar(NAN);
  // record() writes the histories into caller-owned arrays (allocated outside the guarded scope)
  std::vector<std::int8_t> status(static_cast<std::size_t>(T));
  std::vector<Scalar> mass(static_cast<std::size_t>(T * n)), damping(mass.size()),
      stiffness(static_cast<std::size_t>(T * (n + 1)));
  std::unique_ptr<bool[]> valid(new bool[static_cast<std::size_t>(T * n)]);
  const algid::Histories<Scalar> out{status.data(), mass.data(), damping.data(), stiffness.data(), valid.get()};
  bool threw = false;
  long run_allocations = -1, record_allocations = -1, observed = 0;
  double sink = 0;
  try {
    NoAllocationScope scope;
    est.run(rec.a(0), rec.u(0), T, [&](long, algid::Status) {
      sink += static_cast<double>(est.mass()(0));
      ++observed;
    });
    est.reseed();
    est.run(rec.a(0), rec.u(0), T, [&](long, algid::Status) { ++observed; });
    run_allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  try {
    NoAllocationScope scope;
    recorder.record(rec.a(0), rec.u(0), T / 2, out);
    recorder.reseed();
    recorder.record(rec.a(0), rec.u(0), T, out);
    record_allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  std::printf("%s n=%d %s: run() %ld allocations, record() %ld\n", label<Est>(), n,
              sizeof(Scalar) == 4 ? "float" : "double", run_allocations, record_allocations);
  CHECK(!threw);
  CHECK(run_allocations == 0);
  CHECK(record_allocations == 0);
  CHECK(observed == 2 * T);
  CHECK(est.all_valid());
  CHECK(recorder.all_valid() && valid[static_cast<std::size_t>(T * n - 1)] &&
        mass[static_cast<std::size_t>(T * n - 1)] == est.mass()(n - 1));
  (void)sink;
}

// ContinuousEstimator<Dynamic>: update() (warm-up, window results, aggregation, the bad-sample
// path) and reset() under the guard; construction allocates (counted).
template <class Scalar>
void continuous_dynamic_does_not_allocate(int n) {
  using Est = algid::WeakFormContinuousEstimator<Dynamic, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  long constructed = -1;
  std::unique_ptr<Est> owner;
  {
    NoAllocationScope counting;
    Eigen::internal::set_is_malloc_allowed(true);
    owner = std::make_unique<Est>(cfg, n);
    constructed = counting.allocations() - 1;
  }
  Est& est = *owner;
  static_assert(noexcept(est.update(std::declval<const Scalar*>(), std::declval<const Scalar*>())), "update noexcept");
  static_assert(noexcept(est.reset()), "reset noexcept");
  Record<Scalar> rec(n, 4000, 5);
  rec.force[static_cast<std::size_t>(2500 * n)] = Scalar(NAN);
  bool threw = false;
  long allocations = -1;
  long results = 0;
  try {
    NoAllocationScope scope;
    for (long s = 0; s < rec.T; ++s) {
      est.update(rec.a(s), rec.u(s));
      volatile Scalar sink = est.estimate()(0) + est.sigma()(n) + est.mass()(0) + est.stiffness()(n) +
                             est.last_window()(1);
      (void)sink;
    }
    results = est.window_results();
    est.reset();
    for (long s = 0; s < 500; ++s) est.update(rec.a(s), rec.u(s));
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  std::printf(
      "ContinuousEstimator<Dynamic> n=%d %s: construction %ld allocations; update()/reset() over %ld samples "
      "(%ld window results): %ld\n",
      n, sizeof(Scalar) == 4 ? "float" : "double", constructed, rec.T + 500, results, allocations);
  CHECK(!threw);
  CHECK(allocations == 0);
  CHECK(constructed > 0);
  CHECK(results > 20);  // weak-form windows: one every 125 ms, none for 0.5 s after the bad sample
  CHECK(est.dofs() == n && est.params() == 3 * n + 1);
}

// A fixed-size ContinuousEstimator with algebraic windows allocates nothing, construction
// included (placement into static storage: it is too large for some stacks). The weak-form
// windows (the default) size their buffers from the window and the band at construction, on
// the heap (their update() allocates nothing: test_continuous).
void continuous_fixed_construction_does_not_allocate() {
  using Est = algid::AlgebraicContinuousEstimator<3>;
  alignas(Est) static unsigned char storage[sizeof(Est)];
  long allocations = -1;
  bool threw = false;
  try {
    NoAllocationScope scope;
    Est::Config cfg;
    Est* est = new (storage) Est(cfg);
    const double a[3] = {1, 2, 3};
    for (int s = 0; s < 100; ++s) est->update(a, a);
    est->~Est();
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  CHECK(!threw);
  CHECK(allocations == 0);
}

}  // namespace

int main() {
  algid_test::guards_fire();
  no_allocation_in_hot_path<algid::ChainEstimator<1>, double>(1);
  no_allocation_in_hot_path<algid::ChainEstimator<2, float>, float>(2);
  no_allocation_in_hot_path<algid::ChainEstimator<3>, double>(3);
  no_allocation_in_hot_path<algid::ChainEstimator<10>, double>(10);
  no_allocation_in_hot_path<algid::ChainEstimator<3, float>, float>(3);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic>, double>(1);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic>, double>(3);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic>, double>(11);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic>, double>(30);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic, float>, float>(5);
  no_allocation_in_hot_path<algid::ChainEstimator<3>, double>(3, true);
  no_allocation_in_hot_path<algid::ChainEstimator<6>, double>(6, true);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic>, double>(6, true);
  no_allocation_in_hot_path<algid::ChainEstimator<Dynamic, float>, float>(5, true);
  run_does_not_allocate<algid::ChainEstimator<1>, double>(1);
  run_does_not_allocate<algid::ChainEstimator<3>, double>(3);
  run_does_not_allocate<algid::ChainEstimator<10, float>, float>(10);
  run_does_not_allocate<algid::ChainEstimator<Dynamic>, double>(1);
  run_does_not_allocate<algid::ChainEstimator<Dynamic>, double>(3);
  run_does_not_allocate<algid::ChainEstimator<Dynamic>, double>(30);
  run_does_not_allocate<algid::ChainEstimator<Dynamic, float>, float>(10);
  continuous_dynamic_does_not_allocate<double>(3);
  continuous_dynamic_does_not_allocate<double>(10);
  continuous_dynamic_does_not_allocate<float>(3);
  continuous_fixed_construction_does_not_allocate();
  return algid_test::finish("test_realtime");
}
