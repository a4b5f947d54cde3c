// libFuzzer target: ChainEstimator (update(), run(), record()) and WeakFormContinuousEstimator (update())
// fed arbitrary doubles between stretches of a closed-form chain record (SineChainN), built with
// -fsanitize=fuzzer,address,undefined (CMake option ALGID_BUILD_FUZZ, clang only;
// tests/fuzz/estimators.sh builds and runs it). The input is a program:
//   byte 0: the estimator: ChainEstimator<Dynamic> or WeakFormContinuousEstimator<Dynamic> of n = 1..4
//           DOF, or ChainEstimator<3> (the SIMD-lane layout);
//   then ops, each an op byte and its operands:
//     clean k   1..1024 samples of the record (it continues where the last clean stretch ended)
//     raw       one sample of 2n arbitrary doubles, 8 bytes each (NaN payloads, denormals, ...)
//     burst k   k samples whose 2n values each pick one of kSpecial (NaN, inf, DBL_MAX, 1e154,
//               denormals, -0, the clean value x 1e6, the clean value)
//     reset     reseed() / reset()
//     run k     ChainEstimator::record() (and run()) over k clean samples with specials spliced in;
//               WeakFormContinuousEstimator: the same k samples through update()
// Properties (a violation aborts, like a sanitizer report):
//   - every sample holding a NaN or an infinity is BadInput, and the chain estimator never
//     flags valid an estimate that is not a number;
//   - after the program, good samples resume: the chain estimator, reseeded, returns to the
//     truth (mass error < 1e-5 after 600 samples; finite garbage contaminates its growing window
//     until a reseed by design); the continuous estimator, not reset, keeps harvesting windows
//     and is ready with finite running estimates; unless it took in a finite tampered sample
//     (not BadInput, not a dropout: such a sample biases it for good, docs/reliability.md), its
//     masses are within 2 % of the truth after 1.5 s (a clean run: 0.5 %, with the 0.1 s
//     windows used here).
#include <algid/algid.hpp>

#include "closed_form.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

namespace {

using algid::Dynamic;
constexpr double kDt = 1e-3;
constexpr long kRecord = 8192;
constexpr long kProgramSamples = 4096;  // a program ends once it has fed this many (speed)
// The continuous estimator's window [s] and the good samples after the program: short windows
// keep an execution near 0.1 s under the sanitizers.
constexpr double kWindowS = 0.1;
constexpr long kResume = 1500;
constexpr double kResumeError = 0.02;  // its running masses after them (0.5 % on a clean run)
constexpr double kInf = std::numeric_limits<double>::infinity();
const double kSpecial[] = {std::numeric_limits<double>::quiet_NaN(),
                           -std::numeric_limits<double>::quiet_NaN(),
                           kInf,
                           -kInf,
                           DBL_MAX,
                           -DBL_MAX,
                           1e308,
                           1e200,
                           1.4e154,
                           -1e100,
                           4.9e-324,
                           -2.2e-308,
                           0.0,
                           -0.0,
                           0.0,   // slot 14: the clean value x 1e6 (a finite outlier)
                           0.0};  // slot 15: the clean value
constexpr int kSpecials = sizeof(kSpecial) / sizeof(kSpecial[0]);

[[noreturn]] void fail(const char* what, int n) {
  std::fprintf(stderr, "fuzz_estimators: property violated (n = %d): %s\n", n, what);
  std::abort();
}

struct Input {
  const std::uint8_t* data;
  std::size_t size, at = 0;
  bool empty() const { return at >= size; }
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
  double raw() {
    double v = 0;
    std::uint8_t b[8] = {};
    for (auto& x : b) x = byte();
    std::memcpy(&v, b, sizeof v);
    return v;
  }
};

// The chain of n DOF and its record, built once per n.
struct Truth {
  algid_test::SineChainN chain;
  algid_test::Samples rec;
  explicit Truth(int n) : chain(n, 7u + static_cast<unsigned>(n)), rec(chain, kRecord, kDt) {}
};

const Truth& truth_of(int n) {
  static std::unique_ptr<Truth> truths[5];
  if (!truths[n]) truths[n] = std::make_unique<Truth>(n);
  return *truths[n];
}

// A sample of the record with the values an op asks for: 2n floats a then u.
struct Sample {
  std::vector<double> a, u;
  bool tampered = false;  // some value is not the record's
  explicit Sample(int n) : a(static_cast<std::size_t>(n)), u(a) {}
  bool finite() const {
    for (std::size_t i = 0; i < a.size(); ++i)
      if (!std::isfinite(a[i]) || !std::isfinite(u[i])) return false;
    return true;
  }
  void clean(const algid_test::Samples& rec, long s) {
    tampered = false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      a[i] = rec.a(s)[i];
      u[i] = rec.u(s)[i];
    }
  }
  void special(Input& in) {
    for (auto* v : {&a, &u})
      for (auto& x : *v) {
        const int pick = in.byte() % kSpecials;
        x = pick == 14 ? x * 1e6 : pick == 15 ? x : kSpecial[pick];
        tampered |= pick != 15;
      }
  }
};

template <class Est>
struct Driver {
  Est& est;
  int n;
  const algid_test::Samples& rec;
  long pos = 0;
  bool accepted_garbage = false;  // a finite tampered sample the estimator took in
  long fed = 0;                   // samples so far

  void note(bool finite, bool tampered, algid::Status status) {
    if (!finite && status != algid::Status::kBadInput) fail("a non-finite sample was not BadInput", n);
    accepted_garbage |= tampered && status != algid::Status::kBadInput && status != algid::Status::kDropout;
  }
  void check(const Sample& s, algid::Status status) {
    note(s.finite(), s.tampered, status);
    if constexpr (!std::is_same_v<Est, algid::WeakFormContinuousEstimator<Dynamic>>) {
      for (int i = 0; i < n; ++i)
        if (est.valid()(i) && !(std::isfinite(est.mass()(i)) && std::isfinite(est.damping()(i))))
          fail("valid flags an estimate that is not a number", n);
    }
  }
  void feed(const Sample& s) {
    check(s, est.update(s.a.data(), s.u.data()));
    ++fed;
  }
  long next() { return pos = (pos + 1) % kRecord; }
};

// k samples with a special spliced in wherever the input's mask bit says: record() for the
// chain estimator (and its statuses checked like update()'s), update() for the continuous one.
template <class Est>
void run_chunk(Driver<Est>& d, Input& in, Sample& s) {
  const long k = 1 + in.byte();
  const std::uint8_t mask = in.byte();
  std::vector<double> a(static_cast<std::size_t>(k * d.n)), u(a);
  std::vector<char> finite(static_cast<std::size_t>(k)), tampered(finite);
  for (long t = 0; t < k; ++t) {
    s.clean(d.rec, d.next());
    if ((mask >> (t % 8)) & 1) s.special(in);
    finite[static_cast<std::size_t>(t)] = s.finite();
    tampered[static_cast<std::size_t>(t)] = s.tampered;
    std::copy(s.a.begin(), s.a.end(), a.begin() + t * d.n);
    std::copy(s.u.begin(), s.u.end(), u.begin() + t * d.n);
  }
  d.fed += k;
  if constexpr (std::is_same_v<Est, algid::WeakFormContinuousEstimator<Dynamic>>) {
    for (long t = 0; t < k; ++t) {
      const auto i = static_cast<std::size_t>(t);
      d.note(finite[i], tampered[i], d.est.update(a.data() + t * d.n, u.data() + t * d.n));
    }
  } else {
    std::vector<std::int8_t> status(static_cast<std::size_t>(k));
    std::vector<double> mass(static_cast<std::size_t>(k * d.n)), damping(mass),
        spring(static_cast<std::size_t>(k * (d.n + 1)));
    std::unique_ptr<bool[]> valid(new bool[static_cast<std::size_t>(k * d.n)]);
    d.est.record(a.data(), u.data(), k, {status.data(), mass.data(), damping.data(), spring.data(), valid.get()});
    for (long t = 0; t < k; ++t) {
      const auto i = static_cast<std::size_t>(t);
      d.note(finite[i], tampered[i], static_cast<algid::Status>(status[i]));
      for (int i = 0; i < d.n; ++i)
        if (valid[static_cast<std::size_t>(t * d.n + i)] && !std::isfinite(mass[static_cast<std::size_t>(t * d.n + i)]))
          fail("record(): valid flags a mass that is not a number", d.n);
    }
    // the same samples again through run(), the estimator's state carried on
    d.est.run(a.data(), u.data(), k, [&](long t, algid::Status st) {
      d.note(finite[static_cast<std::size_t>(t)], tampered[static_cast<std::size_t>(t)], st);
    });
  }
}

template <class Est>
void program(Driver<Est>& d, Input& in) {
  Sample s(d.n);
  for (int ops = 0; !in.empty() && ops < 64 && d.fed < kProgramSamples; ++ops) {
    const int op = in.byte() % 5;
    if (op == 0) {
      const int k = 1 + 4 * in.byte();
      for (int j = 0; j < k; ++j) {
        s.clean(d.rec, d.next());
        d.feed(s);
      }
    } else if (op == 1) {
      for (auto* v : {&s.a, &s.u})
        for (auto& x : *v) x = in.raw();
      s.tampered = true;
      d.feed(s);
    } else if (op == 2) {
      const int k = 1 + in.byte();
      s.clean(d.rec, d.next());
      s.special(in);
      for (int j = 0; j < k; ++j) d.feed(s);
    } else if (op == 3) {
      if constexpr (std::is_same_v<Est, algid::WeakFormContinuousEstimator<Dynamic>>)
        d.est.reset();
      else
        d.est.reseed();
    } else {
      run_chunk(d, in, s);
    }
  }
}

double worst_mass_error(const Eigen::Ref<const Eigen::VectorXd>& mass, const algid_test::SineChainN& truth) {
  double worst = 0;
  for (int i = 0; i < truth.n; ++i) {
    const double e = std::abs(mass(i) / truth.m[static_cast<std::size_t>(i)] - 1);
    worst = std::isfinite(e) ? std::max(worst, e) : kInf;
  }
  return worst;
}

template <class Est>
void chain(int n, Input& in) {
  typename Est::Config cfg;
  cfg.dt = kDt;
  Est est(cfg, n);
  Driver<Est> d{est, n, truth_of(n).rec};
  program(d, in);
  est.reseed();
  Sample s(n);
  for (int j = 0; j < 600; ++j) {
    s.clean(d.rec, d.next());
    d.feed(s);
  }
  if (!(est.all_valid() && worst_mass_error(est.mass(), truth_of(n).chain) < 1e-5))
    fail("the chain estimator did not return to the truth after a reseed", n);
}

void continuous(int n, Input& in) {
  using Est = algid::WeakFormContinuousEstimator<Dynamic>;
  Est::Config cfg;
  cfg.dt = kDt;
  cfg.window_s = kWindowS;
  // Triage: ALGID_FUZZ_BIAS_COMPENSATION=0 replays a finding without the weak form's bias
  // compensation (the noise estimate's defects, docs/reliability.md finding 11, vanish there).
  const char* bias = std::getenv("ALGID_FUZZ_BIAS_COMPENSATION");
  cfg.bias_compensation = !(bias && bias[0] == '0');
  auto est = std::make_unique<Est>(cfg, n);
  Driver<Est> d{*est, n, truth_of(n).rec};
  program(d, in);
  const long before = est->window_results();
  Sample s(n);
  for (long j = 0; j < kResume; ++j) {
    s.clean(d.rec, d.next());
    d.feed(s);
  }
  if (est->window_results() <= before) fail("the continuous estimator stopped harvesting windows", n);
  for (int j = 0; j < est->params(); ++j)
    if (!std::isfinite(est->estimate()(j)) && !(n == 1 && j == est->params() - 1))
      fail("a running estimate stayed non-finite after good samples resumed", n);
  if (!est->ready()) fail("the continuous estimator is not ready after good samples resumed", n);
  const double error = worst_mass_error(est->estimate().head(n), truth_of(n).chain);
  if (!d.accepted_garbage && error > kResumeError) {
    std::fprintf(stderr, "running estimate's worst mass error %.3g; %ld windows before, %ld after\n", error, before,
                 est->window_results());
    fail("the running masses are not back near the truth", n);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  Input in{data, size};
  const std::uint8_t pick = in.byte();
  const int n = 1 + (pick >> 1) % 4;
  if (pick & 1)
    continuous(n, in);
  else if (n == 3 && (pick & 0x40))
    chain<algid::ChainEstimator<3>>(n, in);
  else
    chain<algid::ChainEstimator<Dynamic>>(n, in);
  return 0;
}
