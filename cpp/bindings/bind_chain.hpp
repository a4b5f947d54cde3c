#pragma once
// The one generic binding helper: bind_chain<N>() exposes ChainEstimator<N> as
// algid._core.ChainEstimatorN. Conversion only, no logic.
#include <algid/algid.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>
#include <utility>

// The ISA variants (module_isa.cpp) register their classes module-locally: the same C++ type
// is bound by several extension modules, each with its own instruction set.
#ifndef ALGID_BINDINGS_MODULE_LOCAL
#define ALGID_BINDINGS_MODULE_LOCAL 0
#endif
// run() through ChainEstimator::run()'s blocks (the wide-register builds) or sample by sample
// through update() (the baseline build: with two-lane SSE2 the blocks gain nothing there, and
// they double the compile time of the 16 chain sizes). Both give the same bits.
#ifndef ALGID_BINDINGS_BLOCK_RUN
#define ALGID_BINDINGS_BLOCK_RUN 0
#endif

namespace algid_bindings {

namespace py = pybind11;

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// (n,) accelerations and forces for a per-sample update(); a ValueError otherwise.
inline void require_sample(const Array& accel, const Array& force, int n) {
  if (accel.ndim() != 1 || accel.shape(0) != n || force.ndim() != 1 || force.shape(0) != n)
    throw py::value_error("update() takes accel and force of shape (" + std::to_string(n) + ",)");
}

/// (T, n) accelerations and forces of one record for run(); a ValueError otherwise.
inline void require_record(const Array& accel, const Array& force, int n) {
  if (accel.ndim() != 2 || accel.shape(1) != n || force.ndim() != 2 || force.shape(1) != n ||
      accel.shape(0) != force.shape(0))
    throw py::value_error("run() takes accel and force of the same shape (T, " + std::to_string(n) + ")");
}

inline algid::Boundary parse_boundary(const std::string& b) {
  if (b == "fixed") return algid::Boundary::kFixed;
  if (b == "free") return algid::Boundary::kFree;
  throw py::value_error("boundary must be 'fixed' or 'free', got '" + b + "'");
}

template <int N>
void bind_chain(py::module_& m) {
  using Est = algid::ChainEstimator<N, double>;
  const std::string name = "ChainEstimator" + std::to_string(N);
  py::class_<Est>(m, name.c_str(), ("Algebraic estimator of a " + std::to_string(N) + "-DOF chain (C++ core).").c_str(),
                  py::module_local(ALGID_BINDINGS_MODULE_LOCAL != 0))
      .def(py::init([](double dt, const std::string& boundary, int min_samples, double min_hadamard) {
             typename Est::Config c;
             c.dt = dt;
             c.boundary = parse_boundary(boundary);
             c.validity.min_samples = min_samples;
             c.validity.min_hadamard = min_hadamard;
             const algid::ConfigError e = Est::validate(c);
             if (e != algid::ConfigError::kNone) throw py::value_error(algid::to_string(e));
             return Est(c);
           }),
           py::arg("dt"), py::arg("boundary") = "fixed", py::arg("min_samples") = 16, py::arg("min_hadamard") = 1e-9)
      .def_readonly_static("n", &Est::kDofs)
      .def_readonly_static("delay_samples", &Est::kDelay)
      .def(
          "update",
          [](Est& e, const Array& accel, const Array& force) {
            require_sample(accel, force, N);
            return static_cast<int>(e.update(accel.data(), force.data()));
          },
          py::arg("accel"), py::arg("force"))
      .def("reseed", &Est::reseed)
      .def_property_readonly("mass", [](const Est& e) { return Array(N, e.mass().data()); })
      .def_property_readonly("damping", [](const Est& e) { return Array(N, e.damping().data()); })
      .def_property_readonly("stiffness", [](const Est& e) { return Array(N + 1, e.stiffness().data()); })
      .def_property_readonly("valid", [](const Est& e) { return e.valid(); })
      .def_property_readonly("samples", &Est::samples)
      .def_property_readonly("window", &Est::window)
      .def("theta", [](const Est& e, int i) { return Array(4, e.theta(i).data()); }, py::arg("dof"))
      .def("theta_instant", [](const Est& e, int i) { return Array(4, e.theta_instant(i).data()); }, py::arg("dof"))
      .def("hadamard", &Est::hadamard, py::arg("dof"))
      .def(
          "run",
          [](Est& e, const Array& accel, const Array& force, bool full) {
            require_record(accel, force, N);
            const py::ssize_t T = accel.shape(0);
            py::array_t<std::int8_t> status(T);
            Array mass({T, static_cast<py::ssize_t>(N)}), damping({T, static_cast<py::ssize_t>(N)});
            Array stiffness({T, static_cast<py::ssize_t>(N + 1)});
            py::array_t<bool> valid({T, static_cast<py::ssize_t>(N)});
            const py::ssize_t Tf = full ? T : 0;
            Array theta({Tf, static_cast<py::ssize_t>(N), py::ssize_t(4)});
            Array theta_instant({Tf, static_cast<py::ssize_t>(N), py::ssize_t(4)});
            Array hadamard({Tf, static_cast<py::ssize_t>(N)});
            const double* a = accel.data();
            const double* f = force.data();
            auto* st = status.mutable_data();
            double* pm = mass.mutable_data();
            double* pc = damping.mutable_data();
            double* pk = stiffness.mutable_data();
            bool* pv = valid.mutable_data();
            double* pt = theta.mutable_data();
            double* pi = theta_instant.mutable_data();
            double* ph = hadamard.mutable_data();
            {
              py::gil_scoped_release release;
              const auto record = [&](long t, algid::Status s) {
                st[t] = static_cast<std::int8_t>(s);
                for (int i = 0; i < N; ++i) {
                  pm[t * N + i] = e.mass()(i);
                  pc[t * N + i] = e.damping()(i);
                  pv[t * N + i] = e.valid()[static_cast<std::size_t>(i)];
                }
                for (int j = 0; j <= N; ++j) pk[t * (N + 1) + j] = e.stiffness()(j);
                if (full) {
                  for (int i = 0; i < N; ++i) {
                    const auto th = e.theta(i);
                    const auto ti = e.theta_instant(i);
                    for (int j = 0; j < 4; ++j) {
                      pt[(t * N + i) * 4 + j] = th(j);
                      pi[(t * N + i) * 4 + j] = ti(j);
                    }
                    ph[t * N + i] = e.hadamard(i);
                  }
                }
              };
#if ALGID_BINDINGS_BLOCK_RUN
              // The block path (ChainEstimator::run): 8 instants per wide register, the same
              // bits as update() sample by sample.
              e.run(a, f, static_cast<long>(T), record);
#else
              for (py::ssize_t t = 0; t < T; ++t) record(static_cast<long>(t), e.update(a + t * N, f + t * N));
#endif
            }
            py::dict out;
            out["status"] = status;
            out["mass"] = mass;
            out["damping"] = damping;
            out["stiffness"] = stiffness;
            out["valid"] = valid;
            if (full) {
              out["theta"] = theta;
              out["theta_instant"] = theta_instant;
              out["hadamard"] = hadamard;
            }
            return out;
          },
          py::arg("accel"), py::arg("force"), py::arg("full") = false,
          "Feed a whole record (T, n) in C++ with the GIL released; returns the estimate histories.");
}

/// Bind ChainEstimator<N> for every N in the pack.
template <int... Ns>
void bind_chains(py::module_& m, std::integer_sequence<int, Ns...>) {
  (bind_chain<Ns>(m), ...);
}

}  // namespace algid_bindings
