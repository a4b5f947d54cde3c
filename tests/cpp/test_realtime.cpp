// The firmware contract, proved: update() and reseed() never allocate (Eigen's runtime malloc
// guard with a throwing eigen_assert, plus a counting global operator new), and are noexcept.
// Negative controls show that both guards fire.
#include "alloc_guard.hpp"  // first: before any Eigen header

#include <algid/algid.hpp>

#include "check.hpp"
#include "closed_form.hpp"

#include <Eigen/Dense>

namespace {

using algid_test::NoAllocationScope;

template <int N, class Scalar>
void no_allocation_in_hot_path() {
  using Est = algid::ChainEstimator<N, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  Est est(cfg);  // configuration phase: may allocate (it does not, but it is allowed to)
  static_assert(noexcept(est.update(std::declval<const Scalar*>(), std::declval<const Scalar*>())), "update noexcept");
  static_assert(noexcept(est.update(std::declval<const algid::Vector<Scalar, N>&>(),
                                    std::declval<const algid::Vector<Scalar, N>&>())),
                "update noexcept");
  static_assert(noexcept(est.reseed()), "reseed noexcept");
  algid_test::SineChain<N> truth(3);
  bool threw = false;
  long allocations = -1;
  try {
    NoAllocationScope scope;
    for (int s = 0; s < 3000; ++s) {
      algid::Vector<Scalar, N> a, u;
      for (int i = 0; i < N; ++i) {
        a(i) = static_cast<Scalar>(truth.accel(i, s * 1e-3));
        u(i) = static_cast<Scalar>(truth.force(i, s * 1e-3));
      }
      if (s == 1000) est.reseed();
      if (s == 2000) a(0) = Scalar(NAN);  // the bad-sample path too
      est.update(a, u);
      volatile Scalar sink = est.mass()(0) + est.stiffness()(N) + est.theta(0)(1) + est.theta_instant(0)(0);
      (void)sink;
    }
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  CHECK(!threw);
  CHECK(allocations == 0);
  CHECK(est.all_valid());
}


// The batch paths too: run() and record() over a whole record (with a bad sample and a reseed)
// allocate nothing either; in the per-DOF layout they went through blocks of instants.
template <int N, class Scalar>
void run_does_not_allocate() {
  using Est = algid::ChainEstimator<N, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  Est est(cfg);
  algid_test::SineChain<N> truth(4);
  constexpr int kT = 1500;
  static Scalar accel[kT * N], force[kT * N];  // outside the guarded scope
  for (int s = 0; s < kT; ++s) {
    for (int i = 0; i < N; ++i) {
      accel[s * N + i] = static_cast<Scalar>(truth.accel(i, s * 1e-3));
      force[s * N + i] = static_cast<Scalar>(truth.force(i, s * 1e-3));
    }
  }
  accel[700 * N] = Scalar(NAN);
  bool threw = false;
  long allocations = -1, blocked = 0;
  double sink = 0;
  // record() writes the histories into caller-owned arrays (outside the guarded scope)
  static std::int8_t status[kT];
  static Scalar mass[kT * N], damping[kT * N], stiffness[kT * (N + 1)];
  static bool valid[kT * N];
  Est recorder(cfg);
  long recorded_blocks = 0, record_allocations = -1;
  try {
    NoAllocationScope scope;
    blocked = est.run(accel, force, kT, [&](long, algid::Status) { sink += static_cast<double>(est.mass()(0)); });
    allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  try {
    NoAllocationScope scope;
    const algid::Histories<Scalar> out{status, mass, damping, stiffness, valid};
    recorded_blocks = recorder.record(accel, force, kT, out);
    record_allocations = scope.allocations();
  } catch (const algid_test::EigenAssertion&) {
    threw = true;
  }
  CHECK(!threw);
  CHECK(allocations == 0);
  CHECK(record_allocations == 0);
  CHECK(recorded_blocks == blocked);
  if constexpr (Est::kLaneLayout) {
    CHECK(blocked == 0);  // update() sample by sample
  } else {
    CHECK(blocked > kT - 40);
  }
  CHECK(est.all_valid());
  CHECK(recorder.all_valid() && valid[kT * N - 1] && mass[kT * N - 1] == est.mass()(N - 1));
  (void)sink;
}

}  // namespace

int main() {
  algid_test::guards_fire();
  no_allocation_in_hot_path<1, double>();
  no_allocation_in_hot_path<2, float>();
  no_allocation_in_hot_path<3, double>();
  no_allocation_in_hot_path<10, double>();
  no_allocation_in_hot_path<3, float>();
  run_does_not_allocate<1, double>();
  run_does_not_allocate<2, double>();
  run_does_not_allocate<3, double>();
  run_does_not_allocate<10, float>();
  return algid_test::finish("test_realtime");
}
