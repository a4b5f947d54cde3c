#pragma once
// Benchmark inputs: closed-form multisine chain trajectories (tests/cpp/closed_form.hpp,
// SineChain) sampled at 1 kHz. For n = 3 the chain carries the Table 1 parameters of the paper.
// Besides the estimator's inputs (accelerations and forces) the RLS baseline gets its
// regressors [y_i, v_i, x_i - x_{i-1}, x_i - x_{i+1}] and target u_i from the same closed form.
#include "closed_form.hpp"

#include <vector>

namespace algid_bench {

/// Sample period of every benchmark signal [s].
constexpr double kDt = 1e-3;

/// Sampled signals of an n-DOF chain, row-major (sample, dof).
template <class Scalar>
struct Signals {
  int samples = 0;
  int dofs = 0;
  std::vector<Scalar> accel;  ///< y_i [m/s^2], samples x dofs
  std::vector<Scalar> force;  ///< u_i [N], samples x dofs
  std::vector<Scalar> phi;    ///< RLS regressors, samples x dofs x 4
};

/// Table 1 of the paper (3-DOF chain with walls at both ends).
template <int N>
void set_table1(algid_test::SineChain<N>& chain) {
  if constexpr (N == 3) {
    chain.m = {2.0, 2.5, 3.0};
    chain.c = {5.5, 5.0, 4.5};
    chain.k = {1000.0, 900.0, 900.0, 700.0};
  }
}

template <int N, class Scalar>
Signals<Scalar> make_signals(int samples, unsigned seed = 7, double dt = kDt, bool with_phi = true) {
  algid_test::SineChain<N> chain(seed);
  set_table1(chain);
  Signals<Scalar> s;
  s.samples = samples;
  s.dofs = N;
  s.accel.resize(static_cast<std::size_t>(samples) * N);
  s.force.resize(static_cast<std::size_t>(samples) * N);
  if (with_phi) s.phi.resize(static_cast<std::size_t>(samples) * N * 4);
  for (int k = 0; k < samples; ++k) {
    const double t = k * dt;
    for (int i = 0; i < N; ++i) {
      const std::size_t at = static_cast<std::size_t>(k) * N + static_cast<std::size_t>(i);
      s.accel[at] = static_cast<Scalar>(chain.accel(i, t));
      s.force[at] = static_cast<Scalar>(chain.force(i, t));
      if (!with_phi) continue;
      const double x = chain.deriv(i, 0, t);
      s.phi[4 * at + 0] = static_cast<Scalar>(chain.accel(i, t));
      s.phi[4 * at + 1] = static_cast<Scalar>(chain.deriv(i, 1, t));
      s.phi[4 * at + 2] = static_cast<Scalar>(x - chain.deriv(i - 1, 0, t));
      s.phi[4 * at + 3] = static_cast<Scalar>(x - chain.deriv(i + 1, 0, t));
    }
  }
  return s;
}

}  // namespace algid_bench
