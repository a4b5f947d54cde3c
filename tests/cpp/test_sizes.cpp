// ChainEstimator::run(), the block path that solves kBlock instants side by side, leaves the
// estimator in the state the per-sample update() leaves it in, to the bit, after every sample:
// estimates, flags, instantaneous solutions, Hadamard ratios and the last system; record()
// writes the histories of those estimates, to the bit, and ends in the same state. Records of
// lengths that are and are not multiples of the block, a bad sample in the middle of a block,
// a reseed between two calls, free and fixed ends, double and float.
#include <algid/chain_estimator.hpp>

#include "check.hpp"
#include "closed_form.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

namespace {

// Equal bits, or both NaN (NaN payloads are not part of the contract).
template <class Scalar>
bool same(Scalar a, Scalar b) {
  if (std::isnan(a) && std::isnan(b)) return true;
  return std::memcmp(&a, &b, sizeof(Scalar)) == 0;
}

template <int N, class Scalar>
long compare_states(const algid::ChainEstimator<N, Scalar>& x, const algid::ChainEstimator<N, Scalar>& y) {
  long differences = 0;
  for (int i = 0; i < N; ++i) {
    differences += !same(x.mass()(i), y.mass()(i)) + !same(x.damping()(i), y.damping()(i));
    differences += x.valid()[static_cast<std::size_t>(i)] != y.valid()[static_cast<std::size_t>(i)];
    differences += x.instant_valid(i) != y.instant_valid(i);
    differences += !same(x.hadamard(i), y.hadamard(i));
    for (int j = 0; j < 4; ++j) {
      differences += !same(x.theta(i)(j), y.theta(i)(j));
      differences += !same(x.theta_instant(i)(j), y.theta_instant(i)(j));
    }
  }
  for (int j = 0; j <= N; ++j) differences += !same(x.stiffness()(j), y.stiffness()(j));
  differences += x.samples() != y.samples();
  return differences;
}

// Histories of T samples in vectors, and a view of them from row t0 on for record().
template <class Scalar>
struct HistoryArrays {
  long T;
  int n;
  std::vector<std::int8_t> status;
  std::vector<Scalar> mass, damping, stiffness;
  std::vector<unsigned char> valid;  // bool, but addressable (std::vector<bool> is not)
  HistoryArrays(long samples, int dofs)
      : T(samples), n(dofs), status(static_cast<std::size_t>(samples), std::int8_t(-1)),
        mass(static_cast<std::size_t>(samples * dofs), Scalar(-1)), damping(mass), stiffness(static_cast<std::size_t>(samples * (dofs + 1)), Scalar(-1)),
        valid(static_cast<std::size_t>(samples * dofs), 2) {}
  algid::Histories<Scalar> view(long t0) {
    static_assert(sizeof(bool) == 1, "bool histories as bytes");
    return {status.data() + t0, mass.data() + t0 * n, damping.data() + t0 * n, stiffness.data() + t0 * (n + 1),
            reinterpret_cast<bool*>(valid.data()) + t0 * n};
  }
  template <class Estimator>
  void put(long t, algid::Status s, const Estimator& e) {
    status[static_cast<std::size_t>(t)] = static_cast<std::int8_t>(s);
    for (int i = 0; i < n; ++i) {
      mass[static_cast<std::size_t>(t * n + i)] = e.mass()(i);
      damping[static_cast<std::size_t>(t * n + i)] = e.damping()(i);
      valid[static_cast<std::size_t>(t * n + i)] = e.valid()[static_cast<std::size_t>(i)];
    }
    for (int j = 0; j <= n; ++j) stiffness[static_cast<std::size_t>(t * (n + 1) + j)] = e.stiffness()(j);
  }
  long differences(const HistoryArrays& other) const {
    long d = 0;
    for (std::size_t k = 0; k < status.size(); ++k) d += status[k] != other.status[k];
    for (std::size_t k = 0; k < mass.size(); ++k) {
      d += !same(mass[k], other.mass[k]) + !same(damping[k], other.damping[k]);
      d += valid[k] != other.valid[k];
    }
    for (std::size_t k = 0; k < stiffness.size(); ++k) d += !same(stiffness[k], other.stiffness[k]);
    return d;
  }
};

// Feeds `record` (T x N accelerations then forces) sample by sample to one estimator and with
// run() to the other, in two calls split at `split`, comparing after every sample.
template <int N, class Scalar>
void bitwise_case(algid::Boundary boundary, long T, long split, long bad_at, unsigned seed) {
  algid_test::SineChain<N> truth(seed);
  std::vector<Scalar> accel(static_cast<std::size_t>(T * N)), force(static_cast<std::size_t>(T * N));
  for (long s = 0; s < T; ++s) {
    for (int i = 0; i < N; ++i) {
      accel[static_cast<std::size_t>(s * N + i)] = static_cast<Scalar>(truth.accel(i, static_cast<double>(s) * 1e-3));
      force[static_cast<std::size_t>(s * N + i)] = static_cast<Scalar>(truth.force(i, static_cast<double>(s) * 1e-3));
    }
  }
  if (bad_at >= 0) force[static_cast<std::size_t>(bad_at * N)] = Scalar(NAN);
  typename algid::ChainEstimator<N, Scalar>::Config cfg;
  cfg.dt = Scalar(1e-3);
  cfg.boundary = boundary;
  algid::ChainEstimator<N, Scalar> one_by_one(cfg), batch(cfg), recorded(cfg);
  // What update() leaves after each sample, as record() writes it.
  HistoryArrays<Scalar> expected_rows(T, N), recorded_rows(T, N);
  long differences = 0, compared = 0, ok = 0, status_mismatch = 0;
  const auto observe = [&](long t, algid::Status status) {
    const algid::Status expected = one_by_one.update(&accel[static_cast<std::size_t>(t * N)],
                                                     &force[static_cast<std::size_t>(t * N)]);
    status_mismatch += status != expected;
    ok += status == algid::Status::kOk;
    differences += compare_states(one_by_one, batch);
    expected_rows.put(t, expected, one_by_one);
    ++compared;
  };
  long blocked = batch.run(accel.data(), force.data(), split, observe);
  blocked += batch.run(accel.data() + split * N, force.data() + split * N, T - split,
                       [&](long t, algid::Status status) { observe(t + split, status); });
  // record(): the same split, the histories written straight into arrays.
  long recorded_blocks = recorded.record(accel.data(), force.data(), split, recorded_rows.view(0));
  recorded_blocks += recorded.record(accel.data() + split * N, force.data() + split * N, T - split,
                                     recorded_rows.view(split));
  const long history_differences = expected_rows.differences(recorded_rows);
  const long end_differences = compare_states(one_by_one, recorded);
  std::printf("N=%d %s %s T=%ld split=%ld bad=%ld: %ld samples compared (%ld kOk, %ld in blocks), %ld differing values; "
              "record(): %ld differing history entries, %ld differing values at the end\n",
              N, boundary == algid::Boundary::kFree ? "free" : "fixed", sizeof(Scalar) == 4 ? "float" : "double", T,
              split, bad_at, compared, ok, blocked, differences, history_differences, end_differences);
  CHECK(compared == T);
  CHECK(status_mismatch == 0);
  CHECK(differences == 0);
  CHECK(history_differences == 0);
  CHECK(end_differences == 0);
  CHECK(recorded_blocks == blocked);
  if constexpr (algid::ChainEstimator<N, Scalar>::kLaneLayout) {
    CHECK(blocked == 0);  // the lane layout's run() is update() sample by sample
  } else {
    // The block path carried the record: per call at most the warm-up (P - 1 samples, again
    // after a bad sample) and a tail shorter than a block go one by one.
    constexpr long P = algid::ChainEstimator<N, Scalar>::kDelay + 2;
    const long singles = 2 * (P - 1 + algid::ChainEstimator<N, Scalar>::kBlock - 1) + (bad_at >= 0 ? P + 8 : 0);
    if (T > 100) CHECK(blocked >= T - singles);
  }
  if (T > 200) CHECK(batch.all_valid());
}

// A bad sample inside what would be a block (per-DOF layout): the block is not taken, update()
// reseeds at the bad sample, and blocks resume once the new window has P - 1 samples. Also in
// the warm-up. And the same in the lane layout.
void bad_sample_inside_block() {
  bitwise_case<2, double>(algid::Boundary::kFixed, 300, 300, 133, 5);
  bitwise_case<2, double>(algid::Boundary::kFixed, 300, 300, 7, 5);  // during the warm-up
  bitwise_case<3, double>(algid::Boundary::kFixed, 300, 300, 133, 5);
}

}  // namespace

int main() {
  bitwise_case<1, double>(algid::Boundary::kFixed, 517, 200, -1, 1);
  bitwise_case<1, double>(algid::Boundary::kFree, 300, 3, -1, 2);
  bitwise_case<2, double>(algid::Boundary::kFree, 300, 150, -1, 3);
  bitwise_case<3, double>(algid::Boundary::kFixed, 1003, 501, -1, 4);
  bitwise_case<3, double>(algid::Boundary::kFixed, 5, 2, -1, 4);  // shorter than a block
  bitwise_case<10, double>(algid::Boundary::kFixed, 400, 0, -1, 6);
  bitwise_case<3, float>(algid::Boundary::kFixed, 600, 301, -1, 7);
  bitwise_case<2, float>(algid::Boundary::kFree, 300, 100, 211, 8);
  bad_sample_inside_block();
  return algid_test::finish("test_block");
}
