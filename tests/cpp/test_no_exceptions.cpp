// Built with -fno-exceptions -fno-rtti -Wall -Wextra -Wconversion -Wshadow -Werror: the headers
// compile for firmware, in double and float, fixed size and Dynamic, and work without exceptions
// (validate() first replaces the constructor's throw, which would abort here).
#include <algid/algid.hpp>

#include <cstdio>

namespace {

int g_passed = 0;
int g_failed = 0;

void check(bool ok, const char* what) {
  if (ok) {
    ++g_passed;
  } else {
    ++g_failed;
    std::printf("FAIL: %s\n", what);
  }
}

// A 3-DOF chain under a smooth force, integrated with a semi-implicit Euler scheme: this checks
// that the code runs and yields finite, valid estimates, not accuracy.
template <class Scalar>
void simulate(int samples, Scalar dt, Scalar* accel, Scalar* force) {
  Scalar x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  const Scalar m[3] = {2, 2.5f, 3}, c[3] = {5.5f, 5, 4.5f}, k[4] = {1000, 900, 900, 700};
  for (int s = 0; s < samples; ++s) {
    const Scalar t = static_cast<Scalar>(s) * dt;
    for (int i = 0; i < 3; ++i) {
      const Scalar u = Scalar(3) * static_cast<Scalar>(i + 1) * t * t;
      const Scalar left = i > 0 ? x[i - 1] : Scalar(0), right = i < 2 ? x[i + 1] : Scalar(0);
      accel[s * 3 + i] = (u - c[i] * v[i] - k[i] * (x[i] - left) - k[i + 1] * (x[i] - right)) / m[i];
      force[s * 3 + i] = u;
    }
    for (int i = 0; i < 3; ++i) {
      v[i] += accel[s * 3 + i] * dt;
      x[i] += v[i] * dt;
    }
  }
}

template <class Scalar, int N>
void chain(const char* label) {
  using Est = algid::ChainEstimator<N, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  check(Est::validate(cfg, 3) == algid::ConfigError::kNone, "validate accepts the configuration");
  typename Est::Config bad = cfg;
  bad.dt = Scalar(0);
  check(Est::validate(bad, 3) == algid::ConfigError::kBadSamplePeriod, "validate rejects dt = 0");
  check(Est::validate(cfg, 0) == algid::ConfigError::kBadDofs, "validate rejects n = 0");
  if (Est::validate(cfg, 3) != algid::ConfigError::kNone) return;
  static Scalar record_a[300 * 3], record_u[300 * 3];
  simulate<Scalar>(300, cfg.dt, record_a, record_u);
  static Est est(cfg, 3), batch(cfg, 3), recorder(cfg, 3);  // static storage (Dynamic: one allocation each, here)
  for (int s = 0; s < 300; ++s) est.update(record_a + s * 3, record_u + s * 3);
  // The batch paths compile under the same flags and end where update() ended.
  long observed = 0;
  batch.run(record_a, record_u, 300, [&](long, algid::Status) { ++observed; });
  const bool same = observed == 300 && batch.mass()(0) == est.mass()(0) && batch.stiffness()(3) == est.stiffness()(3);
  static std::int8_t status[300];
  static Scalar mass[900], damping[900], stiffness[1200];
  static bool valid[900];
  const algid::Histories<Scalar> out{status, mass, damping, stiffness, valid};
  recorder.record(record_a, record_u, 300, out);
  const bool recorded = mass[897] == est.mass()(0) && stiffness[1199] == est.stiffness()(3) && valid[899];
  std::printf("%s: m = %g %g %g, all valid %d\n", label, static_cast<double>(est.mass()(0)),
              static_cast<double>(est.mass()(1)), static_cast<double>(est.mass()(2)), est.all_valid() ? 1 : 0);
  check(est.all_valid(), "valid estimates");
  check(same, "run() ends where update() ended");
  check(recorded, "record() writes what update() gives");
  est.reseed();
  check(!est.all_valid() && est.samples() == 0, "reseed()");
}

template <class Scalar, int N>
void continuous(const char* label) {
  using Est = algid::WeakFormContinuousEstimator<N, Scalar>;
  typename Est::Config cfg;
  cfg.dt = Scalar(1e-3);
  check(Est::validate(cfg, 3) == algid::ContinuousConfigError::kNone, "validate accepts the configuration");
  check(Est::validate(cfg, 0) == algid::ContinuousConfigError::kBadDofs, "validate rejects n = 0");
  typename Est::Config bad = cfg;
  bad.window_s = Scalar(0.001);
  check(Est::validate(bad, 3) == algid::ContinuousConfigError::kBadWindow, "validate rejects a short window");
  if (Est::validate(cfg, 3) != algid::ContinuousConfigError::kNone) return;
  static Scalar record_a[3000 * 3], record_u[3000 * 3];
  simulate<Scalar>(3000, cfg.dt, record_a, record_u);
  static Est est(cfg, 3);
  algid::Status status = algid::Status::kWarmup;
  for (int s = 0; s < 3000; ++s) status = est.update(record_a + s * 3, record_u + s * 3);
  std::printf("%s: %ld window results, ready %d\n", label, est.window_results(), est.ready() ? 1 : 0);
  check(est.window_results() > 15, "window results");  // weak form: one per 125 ms after 0.5 s
  check(status == algid::Status::kOk && est.ready(), "running estimates");
  est.reset();
  check(!est.ready(), "reset()");
}

}  // namespace

int main() {
  chain<double, 3>("ChainEstimator<3>");
  chain<float, 3>("ChainEstimator<3, float>");
  chain<double, algid::Dynamic>("ChainEstimator<Dynamic>(cfg, 3)");
  chain<float, algid::Dynamic>("ChainEstimator<Dynamic, float>(cfg, 3)");
  continuous<double, 3>("ContinuousEstimator<3>");
  continuous<double, algid::Dynamic>("ContinuousEstimator<Dynamic>(cfg, 3)");
  continuous<float, algid::Dynamic>("ContinuousEstimator<Dynamic, float>(cfg, 3)");
  std::printf("test_no_exceptions: %d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}
