// Per-sample cost of ContinuousEstimator<N> (defaults: weak-form windows; and algebraic windows)
// on one uninterrupted closed-form multisine record (signals.hpp) with 40 dB white noise on the
// accelerations: every update() timed with steady_clock over R repetitions of the record.
//
//   continuous_cost [--seconds S] [--reps R]       one JSON object per line, n = 3, 5, 10
//
// Figures per configuration (ns per update, the clock's median overhead subtracted):
//   median, mean, p99, p999 and max over samples of the per-sample-index minimum over the R
//   repetitions (the data-dependent path with the OS's interference filtered out), and the
//   raw worst single update (includes preemption on a shared machine). The first window of
//   samples (warm-up: no window result yet) is left out.
#include <algid/continuous_estimator.hpp>

#include "signals.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

double quantile(const std::vector<double>& sorted, double p) {
  return sorted[static_cast<std::size_t>(p * static_cast<double>(sorted.size() - 1))];
}

template <int N, class Est>
void measure(const char* method, int seconds, int reps) {
  const int T = seconds * 1000;
  auto sig = algid_bench::make_signals<N, double>(T, 7, algid_bench::kDt, false);
  std::mt19937 gen(11);
  std::normal_distribution<double> gauss;
  for (int i = 0; i < N; ++i) {  // 40 dB on every acceleration channel
    double ss = 0;
    for (int t = 0; t < T; ++t)
      ss += sig.accel[static_cast<std::size_t>(t * N + i)] * sig.accel[static_cast<std::size_t>(t * N + i)];
    const double s = 0.01 * std::sqrt(ss / T);
    for (int t = 0; t < T; ++t) sig.accel[static_cast<std::size_t>(t * N + i)] += s * gauss(gen);
  }
  using Clock = std::chrono::steady_clock;
  std::vector<double> overhead(1000);
  for (auto& o : overhead) {
    const auto t0 = Clock::now();
    const auto t1 = Clock::now();
    o = std::chrono::duration<double, std::nano>(t1 - t0).count();
  }
  std::sort(overhead.begin(), overhead.end());
  const double clock_ns = quantile(overhead, 0.5);
  std::vector<double> best(static_cast<std::size_t>(T), 1e300);
  double raw_max = 0, sink = 0;
  long skip = 0;
  for (int r = 0; r < reps; ++r) {
    const typename Est::Config cfg{};
    auto est = std::make_unique<Est>(cfg);
    skip = est->window_samples() + est->settle_samples() + 16;
    for (int t = 0; t < T; ++t) {
      const auto t0 = Clock::now();
      est->update(sig.accel.data() + t * N, sig.force.data() + t * N);
      const auto t1 = Clock::now();
      sink += est->estimate()(0);
      const double ns = std::chrono::duration<double, std::nano>(t1 - t0).count() - clock_ns;
      best[static_cast<std::size_t>(t)] = std::min(best[static_cast<std::size_t>(t)], ns);
      if (t >= skip) raw_max = std::max(raw_max, ns);
    }
  }
  std::vector<double> b(best.begin() + skip, best.end());
  double mean = 0;
  for (double x : b) mean += x;
  mean /= static_cast<double>(b.size());
  std::sort(b.begin(), b.end());
  std::printf(
      "{\"method\": \"%s\", \"n\": %d, \"median_ns\": %.1f, \"mean_ns\": %.1f, \"p99_ns\": %.1f, \"p999_ns\": %.1f, "
      "\"max_path_ns\": %.1f, \"max_over_median\": %.2f, \"raw_max_ns\": %.1f, \"samples\": %zu, \"reps\": %d, "
      "\"sink\": %d}\n",
      method, N, quantile(b, 0.5), mean, quantile(b, 0.99), quantile(b, 0.999), b.back(), b.back() / quantile(b, 0.5),
      raw_max, b.size(), reps, sink == 0.5 ? 1 : 0);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int seconds = 20, reps = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--seconds")) seconds = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
  }
  measure<3, algid::WeakFormContinuousEstimator<3>>("weak_form", seconds, reps);
  measure<5, algid::WeakFormContinuousEstimator<5>>("weak_form", seconds, reps);
  measure<10, algid::WeakFormContinuousEstimator<10>>("weak_form", seconds, reps);
  measure<3, algid::AlgebraicContinuousEstimator<3>>("algebraic", seconds, reps);
  measure<5, algid::AlgebraicContinuousEstimator<5>>("algebraic", seconds, reps);
  measure<10, algid::AlgebraicContinuousEstimator<10>>("algebraic", seconds, reps);
  return 0;
}
