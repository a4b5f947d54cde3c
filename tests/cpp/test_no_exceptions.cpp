// Built with -fno-exceptions -fno-rtti -Wall -Wextra -Wconversion -Werror: the headers compile
// for firmware, in double and float, and work without exceptions (validate() replaces throw).
#include <algid/algid.hpp>

#include <cstdio>

namespace {
template <class Scalar>
int run() {
  using Est = algid::ChainEstimator<3, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  if (Est::validate(cfg) != algid::ConfigError::kNone) return 1;
  typename Est::Config bad = cfg;
  bad.dt = Scalar(0);
  if (Est::validate(bad) != algid::ConfigError::kBadSamplePeriod) return 1;
  static Est est(cfg), batch(cfg);  // static storage: no heap
  static Scalar record_a[300 * 3], record_u[300 * 3];
  // A 3-DOF chain under a smooth force, integrated with a semi-implicit Euler scheme: this
  // checks that the code runs and yields finite, valid estimates, not accuracy.
  Scalar x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  const Scalar m[3] = {2, 2.5f, 3}, c[3] = {5.5f, 5, 4.5f}, k[4] = {1000, 900, 900, 700};
  for (int s = 0; s < 300; ++s) {
    const Scalar t = static_cast<Scalar>(s) * cfg.dt;
    Scalar a[3], u[3];
    for (int i = 0; i < 3; ++i) {
      u[i] = Scalar(3) * static_cast<Scalar>(i + 1) * t * t;
      const Scalar left = i > 0 ? x[i - 1] : Scalar(0), right = i < 2 ? x[i + 1] : Scalar(0);
      a[i] = (u[i] - c[i] * v[i] - k[i] * (x[i] - left) - k[i + 1] * (x[i] - right)) / m[i];
    }
    est.update(a, u);
    for (int i = 0; i < 3; ++i) {
      record_a[s * 3 + i] = a[i];
      record_u[s * 3 + i] = u[i];
    }
    for (int i = 0; i < 3; ++i) {
      v[i] += a[i] * cfg.dt;
      x[i] += v[i] * cfg.dt;
    }
  }
  // The block path compiles under the same flags and ends where update() ended.
  long observed = 0;
  batch.run(record_a, record_u, 300, [&](long, algid::Status) { ++observed; });
  const bool same = observed == 300 && batch.mass()(0) == est.mass()(0) && batch.stiffness()(3) == est.stiffness()(3);
  // So does record(), into statically allocated histories.
  static std::int8_t status[300];
  static Scalar mass[900], damping[900], stiffness[1200];
  static bool valid[900];
  algid::ChainEstimator<3, Scalar> recorder(cfg);
  const algid::Histories<Scalar> out{status, mass, damping, stiffness, valid};
  recorder.record(record_a, record_u, 300, out);
  const bool recorded = mass[897] == est.mass()(0) && stiffness[1199] == est.stiffness()(3) && valid[899];
  return est.all_valid() && same && recorded ? 0 : 1;
}
}  // namespace

int main() {
  const int failures = run<double>() + run<float>();
  std::printf("test_no_exceptions: %d passed, %d failed\n", 2 - failures, failures);
  return failures == 0 ? 0 : 1;
}
