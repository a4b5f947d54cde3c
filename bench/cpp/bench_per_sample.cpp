// Per-sample cost of ChainEstimator<N, Scalar> (and of ChainEstimator<Dynamic, Scalar>, the
// same chain with its size given at run time) and of an RLS baseline of the same parameter count,
// measured in the same run on the same closed-form multisine signals (1 kHz).
//
//   bench_per_sample [--windows W] [--samples T]      timing, one JSON object per line
//   bench_per_sample --callgrind SUBJECT N SCALAR S   S updates between callgrind client
//                                                     requests (run under valgrind
//                                                     --tool=callgrind --instr-atstart=no)
//
//   bench_per_sample --dump N T PATH                  write the n = N signals (T samples): accel
//                                                     then force, row-major float64
//
// Configurations (SUBJECT): "default" = ChainEstimator<N, Scalar> (one window from t0, reseeded
// between timing windows); "dynamic" = ChainEstimator<Dynamic, Scalar>(config, N), the same
// protocol; "continuous" = ContinuousEstimator<N, Scalar> with its default configuration (K = 4
// staggered 0.5 s weak-form windows, joint estimate, change detection), fed one
// uninterrupted signal (never reset between timing windows); "continuous_dynamic" = the same
// with ContinuousEstimator<Dynamic, Scalar>(config, N); "rls" = the baseline; "batch" =
// ChainEstimator<N, Scalar>::record() (what the Python run() calls: update() sample by sample,
// the DOF side by side in SIMD lanes), in 16-sample chunks and whole windows, writing the
// estimate history of every sample into arrays. Every chain row reports its lane layout: "lanes"
// per register and "lane_slots" (lanes in all, the padding included).
//
// Timing protocol, per configuration: one untimed warm-up window, then W windows of T samples
// each (default, dynamic and rls: each starting from reset()/reseed(), not timed):
//   batch  pass: steady_clock around 16 consecutive updates; median and p99 of the mean;
//   single pass: steady_clock around every update minus the clock's own median overhead;
//                max = raw worst single sample (includes whatever the OS did meanwhile),
//                max_path = max over sample index of the min over windows (the worst
//                data-dependent path with interference filtered out).
//   window_min:  whole batch pass of a window / T, min over windows (the protocol of the Python
//                batch run() figure in bench/per_sample.py).
// The first batch (and first 16 single samples) of every window, which contains the
// quadrature's start-up samples (cheaper: no estimate yet), is left out of the statistics.
#include <algid/algid.hpp>
#if defined(__has_include)
#if __has_include(<algid/continuous_estimator.hpp>)
#include <algid/continuous_estimator.hpp>
#define ALGID_BENCH_HAVE_CONTINUOUS 1
#endif
#endif
#ifndef ALGID_BENCH_HAVE_CONTINUOUS
#define ALGID_BENCH_HAVE_CONTINUOUS 0
#endif

#include "rls.hpp"
#include "signals.hpp"

#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define ALGID_BENCH_HAVE_CALLGRIND 1
#endif
#endif
#ifndef ALGID_BENCH_HAVE_CALLGRIND
#define ALGID_BENCH_HAVE_CALLGRIND 0
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

inline long long now_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

// Keeps results observable so the optimiser cannot drop the work.
volatile double g_sink = 0;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const std::size_t at = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(at), v.end());
  return v[at];
}

double clock_overhead_ns() {
  std::vector<double> d(20000);
  for (auto& x : d) {
    const long long a = now_ns();
    const long long b = now_ns();
    x = static_cast<double>(b - a);
  }
  return percentile(d, 0.5);
}

// The chain estimator of a configuration: N fixed, or Dynamic with N given at run time.
template <int N, class Scalar, bool Dyn>
using ChainOf = algid::ChainEstimator<Dyn ? algid::Dynamic : N, Scalar>;

// A subject is timed on segments of its signals: begin(segment) prepares segment `segment`
// (untimed), step(k) consumes its k-th sample.
template <int N, class Scalar, bool Dyn = false>
struct EstimatorSubject {
  using Est = ChainOf<N, Scalar, Dyn>;
  static constexpr int kDofs = N;
  static constexpr bool kContinuous = false;
  static constexpr bool kChunked = false;
  static constexpr int kCallgrindWarmup = 64;
  const algid_bench::Signals<Scalar>* s;
  std::unique_ptr<Est> est;
  explicit EstimatorSubject(const algid_bench::Signals<Scalar>& sig) : s(&sig) {
    typename Est::Config cfg;
    cfg.dt = static_cast<Scalar>(algid_bench::kDt);
    est = std::make_unique<Est>(cfg, N);
  }
  void begin(int) noexcept { est->reseed(); }
  void step(int k) noexcept {
    const std::size_t at = static_cast<std::size_t>(k) * N;
    est->update(s->accel.data() + at, s->force.data() + at);
  }
  double observe() const { return static_cast<double>(est->mass()(0) + est->stiffness()(N)); }
};

// The batch path: ChainEstimator::record() over the same samples, called on chunks of kBatch
// samples, writing the estimate histories the Python run() returns (masses, dampings, springs,
// validity and status of every sample) into arrays.
template <int N, class Scalar>
struct BatchSubject : EstimatorSubject<N, Scalar> {  // the same estimator, fed through record()
  using EstimatorSubject<N, Scalar>::s;
  using EstimatorSubject<N, Scalar>::est;
  static constexpr bool kChunked = true;
  std::vector<Scalar> mass, damping, stiffness;
  std::vector<char> valid;
  std::vector<std::int8_t> status;
  explicit BatchSubject(const algid_bench::Signals<Scalar>& sig)
      : EstimatorSubject<N, Scalar>(sig),
        mass(static_cast<std::size_t>(sig.samples) * N),
        damping(mass.size()),
        stiffness(static_cast<std::size_t>(sig.samples) * (N + 1)),
        valid(mass.size()),
        status(static_cast<std::size_t>(sig.samples)) {}
  // Samples [k0, k0 + count).
  void chunk(int k0, int count) noexcept {
    const std::size_t at = static_cast<std::size_t>(k0) * N;
    algid::Histories<Scalar> out;
    out.status = status.data() + k0;
    out.mass = mass.data() + at;
    out.damping = damping.data() + at;
    out.stiffness = stiffness.data() + static_cast<std::size_t>(k0) * (N + 1);
    out.valid = reinterpret_cast<bool*>(valid.data()) + at;
    est->record(s->accel.data() + at, s->force.data() + at, count, out);
  }
  void step(int k) noexcept { chunk(k, 1); }
  double observe() const { return static_cast<double>(est->mass()(0) + est->stiffness()(N)) + mass[mass.size() / 2]; }
};

#if ALGID_BENCH_HAVE_CONTINUOUS
template <int N, class Scalar, bool Dyn = false>
struct ContinuousSubject {
  using Est = algid::WeakFormContinuousEstimator<Dyn ? algid::Dynamic : N, Scalar>;
  static constexpr int kDofs = N;
  static constexpr bool kContinuous = true;
  static constexpr bool kChunked = false;
  // Past the first window results (0.3 s windows): every window in flight, aggregation running.
  static constexpr int kCallgrindWarmup = 400;
  const algid_bench::Signals<Scalar>* s;
  std::unique_ptr<Est> est;
  int segment_samples;
  std::size_t base = 0;
  ContinuousSubject(const algid_bench::Signals<Scalar>& sig, int segment) : s(&sig), segment_samples(segment) {
    typename Est::Config cfg;
    cfg.dt = static_cast<Scalar>(algid_bench::kDt);
    est = std::make_unique<Est>(cfg, N);
  }
  explicit ContinuousSubject(const algid_bench::Signals<Scalar>& sig) : ContinuousSubject(sig, sig.samples) {}
  // Never reset: consecutive segments are consecutive stretches of one signal.
  void begin(int segment) noexcept {
    base = static_cast<std::size_t>(segment) * static_cast<std::size_t>(segment_samples);
  }
  void step(int k) noexcept {
    const std::size_t at = (base + static_cast<std::size_t>(k)) * N;
    est->update(s->accel.data() + at, s->force.data() + at);
  }
  double observe() const { return static_cast<double>(est->estimate()(0)); }
};
#endif

template <int N, class Scalar>
struct RlsSubject {
  static constexpr int kDofs = N;
  static constexpr bool kContinuous = false;
  static constexpr bool kChunked = false;
  static constexpr int kCallgrindWarmup = 64;
  const algid_bench::Signals<Scalar>* s;
  std::array<algid_bench::Rls4<Scalar>, N> rls{};
  explicit RlsSubject(const algid_bench::Signals<Scalar>& sig) : s(&sig) {}
  void begin(int) noexcept {
    for (auto& r : rls) r.reset();
  }
  void step(int k) noexcept {
    const std::size_t at = static_cast<std::size_t>(k) * N;
    for (int i = 0; i < N; ++i)
      rls[static_cast<std::size_t>(i)].update(s->phi.data() + 4 * (at + static_cast<std::size_t>(i)),
                                              s->force[at + static_cast<std::size_t>(i)]);
  }
  double observe() const { return static_cast<double>(rls[0].theta()(0)); }
};

struct Result {
  double batch_median = 0, batch_p99 = 0, single_median = 0, single_p99 = 0, max = 0, max_path = 0;
  double window_min = 1e300;
  long timed = 0;
};

constexpr int kBatch = 16;

template <class Subject>
Result measure(Subject& subject, int samples, int windows, double overhead) {
  std::vector<double> batch;
  std::vector<double> single;
  std::vector<double> path(static_cast<std::size_t>(samples), 1e300);
  const int batches = samples / kBatch;
  Result r;
  for (int w = 0; w <= windows; ++w) {
    const bool warmup = w == 0;
    subject.begin(2 * w);
    double window_ns = 0;
    for (int b = 0; b < batches; ++b) {
      const long long t0 = now_ns();
      for (int k = b * kBatch; k < (b + 1) * kBatch; ++k) subject.step(k);
      const long long t1 = now_ns();
      window_ns += static_cast<double>(t1 - t0);
      if (!warmup && b > 0) batch.push_back(static_cast<double>(t1 - t0) / kBatch);
    }
    if (!warmup) r.window_min = std::min(r.window_min, window_ns / (batches * kBatch));
    g_sink = g_sink + subject.observe();
    subject.begin(2 * w + 1);
    for (int k = 0; k < batches * kBatch; ++k) {
      const long long t0 = now_ns();
      subject.step(k);
      const long long t1 = now_ns();
      if (!warmup && k >= kBatch) {
        const double d = std::max(0.0, static_cast<double>(t1 - t0) - overhead);
        single.push_back(d);
        path[static_cast<std::size_t>(k)] = std::min(path[static_cast<std::size_t>(k)], d);
      }
    }
    g_sink = g_sink + subject.observe();
  }
  r.batch_median = percentile(batch, 0.5);
  r.batch_p99 = percentile(batch, 0.99);
  r.single_median = percentile(single, 0.5);
  r.single_p99 = percentile(single, 0.99);
  r.max = single.empty() ? 0 : *std::max_element(single.begin(), single.end());
  for (int k = kBatch; k < batches * kBatch; ++k) r.max_path = std::max(r.max_path, path[static_cast<std::size_t>(k)]);
  r.timed = static_cast<long>(single.size());
  return r;
}

// Batch timing: kBatch-sample chunks through record() (median / p99 per chunk, as the
// per-sample protocol's batches) and whole windows in one record() call (window_min). No
// single-sample times: a chunk is the unit of work; max is the slowest chunk.
template <class Subject>
Result measure_batch(Subject& subject, int samples, int windows) {
  std::vector<double> batch;
  const int batches = samples / kBatch;
  Result r;
  double slowest = 0;
  for (int w = 0; w <= windows; ++w) {
    const bool warmup = w == 0;
    subject.begin(2 * w);
    for (int b = 0; b < batches; ++b) {
      const long long t0 = now_ns();
      subject.chunk(b * kBatch, kBatch);
      const long long t1 = now_ns();
      if (!warmup && b > 0) {
        batch.push_back(static_cast<double>(t1 - t0) / kBatch);
        slowest = std::max(slowest, static_cast<double>(t1 - t0) / kBatch);
      }
    }
    g_sink = g_sink + subject.observe();
    subject.begin(2 * w + 1);
    const long long t0 = now_ns();
    subject.chunk(0, batches * kBatch);
    const long long t1 = now_ns();
    if (!warmup) r.window_min = std::min(r.window_min, static_cast<double>(t1 - t0) / (batches * kBatch));
    g_sink = g_sink + subject.observe();
  }
  r.batch_median = percentile(batch, 0.5);
  r.batch_p99 = percentile(batch, 0.99);
  r.single_median = r.batch_median;
  r.single_p99 = r.batch_p99;
  r.max = slowest;
  r.max_path = slowest;
  r.timed = static_cast<long>(batch.size()) * kBatch;
  return r;
}

// The SIMD layout of a chain estimator in this build: one DOF per lane, `lanes` lanes per
// register, `slots` lanes in all (the padding included).
template <int N, class Scalar, bool Dyn = false>
struct LayoutInfo {
  using Est = ChainOf<N, Scalar, Dyn>;
  static const char* name() { return "lanes"; }
  static int lanes() { return Est::kLanes; }
  static int slots() { return (N + Est::kLanes - 1) / Est::kLanes * Est::kLanes; }
};

void print(const char* config, int n, const char* scalar, const Result& r, double overhead, const char* layout = "",
           int lanes = 0, int slots = 0) {
  const double dn = n;
  std::printf(
      "{\"config\": \"%s\", \"n\": %d, \"scalar\": \"%s\", "
      "\"ns_per_sample_median\": %.2f, \"ns_per_dof_sample_median\": %.2f, \"p99\": %.2f, \"max\": %.2f, "
      "\"max_path\": %.2f, \"window_min\": %.2f, \"single_median\": %.2f, \"single_p99\": %.2f, \"timed_samples\": "
      "%ld, "
      "\"clock_overhead_ns\": %.1f, \"batch\": %d, \"layout\": \"%s\", \"lanes\": %d, \"lane_slots\": %d, "
      "\"units\": \"ns per DOF-sample except ns_per_sample_median\"}\n",
      config, n, scalar, r.batch_median, r.batch_median / dn, r.batch_p99 / dn, r.max / dn, r.max_path / dn,
      r.window_min / dn, r.single_median / dn, r.single_p99 / dn, r.timed, overhead, kBatch, layout, lanes, slots);
  std::fflush(stdout);
}

template <int N, class Scalar>
void bench_n(const char* scalar, int samples, int windows, double overhead) {
  {
    const auto sig = algid_bench::make_signals<N, Scalar>(samples);
    {
      EstimatorSubject<N, Scalar> subject(sig);
      print("default", N, scalar, measure(subject, samples, windows, overhead), overhead, LayoutInfo<N, Scalar>::name(),
            LayoutInfo<N, Scalar>::lanes(), LayoutInfo<N, Scalar>::slots());
    }
    {
      EstimatorSubject<N, Scalar, true> subject(sig);
      print("dynamic", N, scalar, measure(subject, samples, windows, overhead), overhead,
            LayoutInfo<N, Scalar, true>::name(), LayoutInfo<N, Scalar, true>::lanes(),
            LayoutInfo<N, Scalar, true>::slots());
    }
    {
      BatchSubject<N, Scalar> subject(sig);
      print("batch", N, scalar, measure_batch(subject, samples, windows), overhead, LayoutInfo<N, Scalar>::name(),
            LayoutInfo<N, Scalar>::lanes(), LayoutInfo<N, Scalar>::slots());
    }
    {
      RlsSubject<N, Scalar> subject(sig);
      print("rls", N, scalar, measure(subject, samples, windows, overhead), overhead);
    }
  }
#if ALGID_BENCH_HAVE_CONTINUOUS
  {
    // One uninterrupted signal: 2 segments (batch and single pass) per window. Segments are a
    // whole number of result periods (window samples / stagger) long, so that sample index k
    // has the same place in the harvest schedule in every segment (max_path needs that).
    const typename algid::WeakFormContinuousEstimator<N, Scalar>::Config cfg{};
    const int period = static_cast<int>(std::lround(cfg.window_s / static_cast<Scalar>(algid_bench::kDt))) /
                       cfg.stagger;
    const int segment = (samples + period - 1) / period * period;
    const auto sig = algid_bench::make_signals<N, Scalar>(2 * (windows + 1) * segment, 7, algid_bench::kDt, false);
    {
      ContinuousSubject<N, Scalar> subject(sig, segment);
      print("continuous", N, scalar, measure(subject, segment, windows, overhead), overhead);
    }
    {
      ContinuousSubject<N, Scalar, true> subject(sig, segment);
      print("continuous_dynamic", N, scalar, measure(subject, segment, windows, overhead), overhead);
    }
  }
#endif
}

template <class Subject, class Scalar>
int callgrind_run(int updates) {
  constexpr int kWarm = Subject::kCallgrindWarmup;
  const int total = kWarm + updates;
  const auto sig = algid_bench::make_signals<Subject::kDofs, Scalar>(total);
  Subject subject(sig);
  subject.begin(0);
  for (int k = 0; k < kWarm; ++k) subject.step(k);
  CALLGRIND_START_INSTRUMENTATION;
  if constexpr (Subject::kChunked) {
    subject.chunk(kWarm, updates);  // one run() call
  } else {
    for (int k = kWarm; k < total; ++k) subject.step(k);
  }
  CALLGRIND_STOP_INSTRUMENTATION;
  g_sink = g_sink + subject.observe();
  std::printf("{\"callgrind_client_requests\": %d, \"updates\": %d, \"warmup\": %d}\n", ALGID_BENCH_HAVE_CALLGRIND,
              updates, kWarm);
  return 0;
}

template <int N>
int callgrind_dispatch(const std::string& subject, const std::string& scalar, int updates) {
  if (subject == "default" && scalar == "double") return callgrind_run<EstimatorSubject<N, double>, double>(updates);
  if (subject == "default" && scalar == "float") return callgrind_run<EstimatorSubject<N, float>, float>(updates);
  if (subject == "dynamic" && scalar == "double")
    return callgrind_run<EstimatorSubject<N, double, true>, double>(updates);
  if (subject == "dynamic" && scalar == "float") return callgrind_run<EstimatorSubject<N, float, true>, float>(updates);
  if (subject == "batch" && scalar == "double") return callgrind_run<BatchSubject<N, double>, double>(updates);
  if (subject == "batch" && scalar == "float") return callgrind_run<BatchSubject<N, float>, float>(updates);
  if (subject == "rls" && scalar == "double") return callgrind_run<RlsSubject<N, double>, double>(updates);
  if (subject == "rls" && scalar == "float") return callgrind_run<RlsSubject<N, float>, float>(updates);
#if ALGID_BENCH_HAVE_CONTINUOUS
  if (subject == "continuous" && scalar == "double")
    return callgrind_run<ContinuousSubject<N, double>, double>(updates);
  if (subject == "continuous" && scalar == "float") return callgrind_run<ContinuousSubject<N, float>, float>(updates);
  if (subject == "continuous_dynamic" && scalar == "double")
    return callgrind_run<ContinuousSubject<N, double, true>, double>(updates);
  if (subject == "continuous_dynamic" && scalar == "float")
    return callgrind_run<ContinuousSubject<N, float, true>, float>(updates);
#endif
  std::fprintf(stderr, "unknown subject/scalar %s/%s\n", subject.c_str(), scalar.c_str());
  return 2;
}

template <int N>
int dump(int samples, const char* path) {
  const auto sig = algid_bench::make_signals<N, double>(samples, 7, algid_bench::kDt, false);
  std::FILE* f = std::fopen(path, "wb");
  if (!f) return 1;
  const bool ok = std::fwrite(sig.accel.data(), sizeof(double), sig.accel.size(), f) == sig.accel.size() &&
                  std::fwrite(sig.force.data(), sizeof(double), sig.force.size(), f) == sig.force.size();
  return std::fclose(f) == 0 && ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  int windows = 10;
  int samples = 2000;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--windows") && a + 1 < argc) {
      windows = std::atoi(argv[++a]);
    } else if (!std::strcmp(argv[a], "--samples") && a + 1 < argc) {
      samples = std::atoi(argv[++a]);
    } else if (!std::strcmp(argv[a], "--dump") && a + 3 < argc) {
      const int n = std::atoi(argv[a + 1]);
      const int t = std::atoi(argv[a + 2]);
      switch (n) {
        case 1: return dump<1>(t, argv[a + 3]);
        case 3: return dump<3>(t, argv[a + 3]);
        case 10: return dump<10>(t, argv[a + 3]);
        case 50: return dump<50>(t, argv[a + 3]);
        default: std::fprintf(stderr, "n must be 1, 3, 10 or 50\n"); return 2;
      }
    } else if (!std::strcmp(argv[a], "--callgrind") && a + 4 < argc) {
      const std::string subject = argv[a + 1];
      const int n = std::atoi(argv[a + 2]);
      const std::string scalar = argv[a + 3];
      const int updates = std::atoi(argv[a + 4]);
      switch (n) {
        case 1: return callgrind_dispatch<1>(subject, scalar, updates);
        case 3: return callgrind_dispatch<3>(subject, scalar, updates);
        case 10: return callgrind_dispatch<10>(subject, scalar, updates);
        case 50: return callgrind_dispatch<50>(subject, scalar, updates);
        default: std::fprintf(stderr, "n must be 1, 3, 10 or 50\n"); return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: %s [--windows W] [--samples T] | --callgrind SUBJECT N SCALAR UPDATES | --dump N T PATH\n",
                   argv[0]);
      return 2;
    }
  }
  if (samples < 4 * kBatch || windows < 1) {
    std::fprintf(stderr, "need --samples >= %d and --windows >= 1\n", 4 * kBatch);
    return 2;
  }
  const double overhead = clock_overhead_ns();
  bench_n<1, double>("double", samples, windows, overhead);
  bench_n<3, double>("double", samples, windows, overhead);
  bench_n<10, double>("double", samples, windows, overhead);
  bench_n<50, double>("double", samples, windows, overhead);
  bench_n<1, float>("float", samples, windows, overhead);
  bench_n<3, float>("float", samples, windows, overhead);
  bench_n<10, float>("float", samples, windows, overhead);
  bench_n<50, float>("float", samples, windows, overhead);
  return g_sink == 12345.678 ? 1 : 0;
}
