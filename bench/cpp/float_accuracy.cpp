// Single versus double precision on the Table 1 chain (m = 2, 2.5, 3 kg; c = 5.5, 5, 4.5 N s/m;
// k = 1000, 900, 900, 700 N/m; walls at both ends), noise-free, 1 kHz.
//
// Two signal sources, both computed in double and rounded to the estimator's Scalar:
//   closed_form  prescribed multisine motion, forces from eq. 1 in closed form (SineChain);
//   rk4          the plant from rest under a multisine force, RK4 with 64 substeps per sample
//                (local error ~1e-16 relative: the signals are exact to double rounding).
// Prints one JSON object per (source, scalar, rate): the worst relative error over the 10
// parameters at t0 + 0.05 .. 20 s (t = time of the newest sample), and the worst relative
// error over t in [0.1 s, end]. 1 kHz runs 20 s (the window grows from t0: no reseeding);
// 10 and 20 kHz run 1 s.
#include <algid/chain_estimator.hpp>

#include "signals.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

constexpr double kM[3] = {2.0, 2.5, 3.0};
constexpr double kC[3] = {5.5, 5.0, 4.5};
constexpr double kK[4] = {1000.0, 900.0, 900.0, 700.0};

// Multisine force [N] on DOF i: three tones between 1.3 and 17 Hz, distinct per DOF.
double force_of(int i, double t) {
  const double f[3] = {1.3 + 0.7 * i, 5.1 + 1.9 * i, 11.0 + 3.1 * i};
  const double a[3] = {10.0, 6.0, 4.0};
  double u = 0;
  for (int q = 0; q < 3; ++q) u += a[q] * std::sin(2 * M_PI * f[q] * t + 0.9 * q + 0.4 * i);
  return u;
}

void accel_of(const double* x, const double* v, double t, double* a) {
  for (int i = 0; i < 3; ++i) {
    const double left = i > 0 ? x[i - 1] : 0.0, right = i < 2 ? x[i + 1] : 0.0;
    a[i] = (force_of(i, t) - kC[i] * v[i] - kK[i] * (x[i] - left) - kK[i + 1] * (x[i] - right)) / kM[i];
  }
}

// Accelerations and forces of the plant from rest, sampled every dt.
void simulate_rk4(int samples, double dt, std::vector<double>& accel, std::vector<double>& force) {
  constexpr int kSub = 64;
  const double h = dt / kSub;
  double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  accel.resize(static_cast<std::size_t>(samples) * 3);
  force.resize(static_cast<std::size_t>(samples) * 3);
  for (int k = 0; k < samples; ++k) {
    const double t = k * dt;
    double a[3];
    accel_of(x, v, t, a);
    for (int i = 0; i < 3; ++i) {
      accel[static_cast<std::size_t>(3 * k + i)] = a[i];
      force[static_cast<std::size_t>(3 * k + i)] = force_of(i, t);
    }
    for (int s = 0; s < kSub; ++s) {
      const double ts = t + s * h;
      double k1x[3], k1v[3], k2x[3], k2v[3], k3x[3], k3v[3], k4x[3], k4v[3], xt[3], vt[3];
      for (int i = 0; i < 3; ++i) k1x[i] = v[i];
      accel_of(x, v, ts, k1v);
      for (int i = 0; i < 3; ++i) xt[i] = x[i] + 0.5 * h * k1x[i], vt[i] = v[i] + 0.5 * h * k1v[i];
      for (int i = 0; i < 3; ++i) k2x[i] = vt[i];
      accel_of(xt, vt, ts + 0.5 * h, k2v);
      for (int i = 0; i < 3; ++i) xt[i] = x[i] + 0.5 * h * k2x[i], vt[i] = v[i] + 0.5 * h * k2v[i];
      for (int i = 0; i < 3; ++i) k3x[i] = vt[i];
      accel_of(xt, vt, ts + 0.5 * h, k3v);
      for (int i = 0; i < 3; ++i) xt[i] = x[i] + h * k3x[i], vt[i] = v[i] + h * k3v[i];
      for (int i = 0; i < 3; ++i) k4x[i] = vt[i];
      accel_of(xt, vt, ts + h, k4v);
      for (int i = 0; i < 3; ++i) {
        x[i] += h / 6 * (k1x[i] + 2 * k2x[i] + 2 * k3x[i] + k4x[i]);
        v[i] += h / 6 * (k1v[i] + 2 * k2v[i] + 2 * k3v[i] + k4v[i]);
      }
    }
  }
}

// ChainEstimator<3, Scalar> fed with double signals rounded to Scalar.
template <class Scalar>
class CoreEstimator3 {
 public:
  explicit CoreEstimator3(double dt) : est_(config(dt)) {}
  void update(const double* accel, const double* force) {
    Scalar a[3], u[3];
    for (int i = 0; i < 3; ++i) a[i] = static_cast<Scalar>(accel[i]), u[i] = static_cast<Scalar>(force[i]);
    est_.update(a, u);
  }
  std::array<double, 10> params() const {
    std::array<double, 10> p{};
    for (int i = 0; i < 3; ++i) {
      p[static_cast<std::size_t>(i)] = static_cast<double>(est_.mass()(i));
      p[static_cast<std::size_t>(3 + i)] = static_cast<double>(est_.damping()(i));
    }
    for (int j = 0; j < 4; ++j) p[static_cast<std::size_t>(6 + j)] = static_cast<double>(est_.stiffness()(j));
    return p;
  }

 private:
  static typename algid::ChainEstimator<3, Scalar>::Config config(double dt) {
    typename algid::ChainEstimator<3, Scalar>::Config cfg;
    cfg.dt = static_cast<Scalar>(dt);
    return cfg;
  }
  algid::ChainEstimator<3, Scalar> est_;
};

template <class Estimator>
void run(const char* source, const char* scalar, const std::vector<double>& accel, const std::vector<double>& force,
         int samples, double dt) {
  constexpr int kChecks = 9;
  Estimator est(dt);
  const double truth[10] = {kM[0], kM[1], kM[2], kC[0], kC[1], kC[2], kK[0], kK[1], kK[2], kK[3]};
  const double checkpoints[kChecks] = {0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0};
  std::array<double, kChecks> at_checkpoint{};
  at_checkpoint.fill(NAN);
  std::array<double, 10> worst_param{};
  double worst_after = 0;
  for (int k = 0; k < samples; ++k) {
    est.update(accel.data() + 3 * k, force.data() + 3 * k);
    const double t = k * dt;
    const std::array<double, 10> p = est.params();
    std::array<double, 10> per{};
    double e = 0;
    for (std::size_t j = 0; j < 10; ++j) {
      per[j] = std::abs(p[j] / truth[j] - 1);
      e = std::isnan(per[j]) ? INFINITY : std::max(e, per[j]);
    }
    for (int c = 0; c < kChecks; ++c)
      if (std::abs(t - checkpoints[c]) < 0.5 * dt) at_checkpoint[static_cast<std::size_t>(c)] = e;
    if (t >= 0.1 - 0.5 * dt) {
      worst_after = std::max(worst_after, e);
      for (std::size_t j = 0; j < 10; ++j) worst_param[j] = std::max(worst_param[j], per[j]);
    }
  }
  std::printf("{\"source\": \"%s\", \"scalar\": \"%s\", \"rate_hz\": %.0f, \"max_rel_error_at\": {", source, scalar,
              1.0 / dt);
  bool first = true;
  for (int c = 0; c < kChecks; ++c) {
    if (std::isnan(at_checkpoint[static_cast<std::size_t>(c)])) continue;
    std::printf("%s\"%.2f\": %.3e", first ? "" : ", ", checkpoints[c], at_checkpoint[static_cast<std::size_t>(c)]);
    first = false;
  }
  std::printf("}, \"max_rel_error_after_0.1s\": %.3e, \"per_parameter_max_after_0.1s\": [", worst_after);
  for (std::size_t j = 0; j < 10; ++j) std::printf("%s%.2e", j ? ", " : "", worst_param[j]);
  std::printf("], \"parameters\": \"m1 m2 m3 c1 c2 c3 k1 k2 k3 k4\"}\n");
  std::fflush(stdout);
}

void run_all(const char* source, const std::vector<double>& accel, const std::vector<double>& force, int samples,
             double dt) {
  run<CoreEstimator3<double>>(source, "double", accel, force, samples, dt);
  run<CoreEstimator3<float>>(source, "float", accel, force, samples, dt);
}

}  // namespace

int main() {
  for (const double rate : {1000.0, 10000.0, 20000.0}) {
    const double dt = 1.0 / rate;
    const int samples = static_cast<int>((rate == 1000.0 ? 20.0 : 1.0) * rate) + 1;
    std::vector<double> accel, force;
    {
      // Closed form with Table 1 parameters (set_table1 overrides SineChain's random ones).
      const auto s = algid_bench::make_signals<3, double>(samples, 7, dt);
      run_all("closed_form", s.accel, s.force, samples, dt);
    }
    simulate_rk4(samples, dt, accel, force);
    run_all("rk4", accel, force, samples, dt);
  }
  return 0;
}
