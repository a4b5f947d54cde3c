#pragma once
// The one generic binding helper: bind_chain<N>() exposes ChainEstimator<N> as
// algid._core.ChainEstimatorN. Conversion only, no logic.
#include <algid/algid.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

// The ISA variants (module_isa.cpp) register their classes module-locally: the same C++ type
// is bound by several extension modules, each with its own instruction set.
#ifndef ALGID_BINDINGS_MODULE_LOCAL
#define ALGID_BINDINGS_MODULE_LOCAL 0
#endif
// run() through ChainEstimator::run() (the wide-register builds: blocks of 8 instants for one
// or two DOF) or sample by sample through update() (the baseline build: with two-lane SSE2 the
// blocks gain nothing, and they double the compile time). Both give the same bits.
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

/// The histories run() returns, carved out of one numpy allocation: a record of many DOF
/// returns megabytes, and one buffer (rather than one per history) lets the allocator reuse the
/// same pages from call to call instead of faulting fresh ones in (about 10 ns per DOF-sample
/// at n = 50 otherwise). Each history is a C-contiguous view whose base is the buffer. The
/// bookkeeping is fixed-size (no heap beyond numpy's): at n = 1 a whole call costs about as
/// much as 100 samples, so its fixed part shows.
class RecordBuffer {
 public:
  /// One history: its name, its type ('d' float64, '?' bool, 'b' int8) and shape.
  struct History {
    const char* name;
    char kind;
    int ndim;
    py::ssize_t shape[3];
  };

  /// Add a history (before allocate()).
  void add(const History& h) {
    if (count_ == kMax) throw std::logic_error("RecordBuffer: too many histories");
    std::size_t elements = 1;
    for (int d = 0; d < h.ndim; ++d) elements *= static_cast<std::size_t>(h.shape[d]);
    const std::size_t item = h.kind == 'd' ? sizeof(double) : 1;
    slots_[count_++] = {h, bytes_};
    bytes_ += (elements * item + 63) / 64 * 64;  // every history on its own cache lines
  }
  /// The one numpy allocation for every history added.
  void allocate() { buffer_ = py::array_t<std::uint8_t>(static_cast<py::ssize_t>(bytes_ > 0 ? bytes_ : 1)); }

  double* f8(const char* name) { return reinterpret_cast<double*>(at(name)); }
  bool* boolean(const char* name) { return reinterpret_cast<bool*>(at(name)); }
  std::int8_t* int8(const char* name) { return reinterpret_cast<std::int8_t*>(at(name)); }

  /// {name: view} of every history.
  py::dict views() {
    py::dict out;
    for (int k = 0; k < count_; ++k) {
      const Slot& s = slots_[k];
      const py::dtype type = s.history.kind == 'd'   ? py::dtype::of<double>()
                             : s.history.kind == '?' ? py::dtype::of<bool>()
                                                     : py::dtype::of<std::int8_t>();
      out[s.history.name] = py::array(type, std::vector<py::ssize_t>(s.history.shape, s.history.shape + s.history.ndim),
                                      {}, buffer_.mutable_data() + s.offset, buffer_);
    }
    return out;
  }

 private:
  static constexpr int kMax = 8;
  struct Slot {
    History history;
    std::size_t offset;
  };
  std::uint8_t* at(const char* name) {
    for (int k = 0; k < count_; ++k)
      if (std::strcmp(slots_[k].history.name, name) == 0) return buffer_.mutable_data() + slots_[k].offset;
    throw std::logic_error(std::string("RecordBuffer: no history ") + name);
  }
  std::array<Slot, kMax> slots_{};
  int count_ = 0;
  std::size_t bytes_ = 0;
  py::array_t<std::uint8_t> buffer_;
};

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
            const py::ssize_t n = N;
            RecordBuffer out;
            out.add({"mass", 'd', 2, {T, n}});
            out.add({"damping", 'd', 2, {T, n}});
            out.add({"stiffness", 'd', 2, {T, n + 1}});
            if (full) {
              out.add({"theta", 'd', 3, {T, n, 4}});
              out.add({"theta_instant", 'd', 3, {T, n, 4}});
              out.add({"hadamard", 'd', 2, {T, n}});
            }
            out.add({"valid", '?', 2, {T, n}});
            out.add({"status", 'b', 1, {T}});
            out.allocate();
            const double* a = accel.data();
            const double* f = force.data();
            const algid::Histories<double> histories{out.int8("status"), out.f8("mass"), out.f8("damping"),
                                                     out.f8("stiffness"), out.boolean("valid")};
            double* pt = full ? out.f8("theta") : nullptr;
            double* pi = full ? out.f8("theta_instant") : nullptr;
            double* ph = full ? out.f8("hadamard") : nullptr;
            {
              py::gil_scoped_release release;
              const auto record = [&](long t, algid::Status s) {
                e.write_row(t, s, histories);
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
              // Blocks of 8 instants in the per-DOF layout (N <= 2), update() sample by sample
              // in the lane layout; the same bits as update(). The default histories straight
              // from ChainEstimator::record(); the per-DOF extras through run()'s observer.
              if (full) {
                e.run(a, f, static_cast<long>(T), record);
              } else {
                e.record(a, f, static_cast<long>(T), histories);
              }
#else
              for (py::ssize_t t = 0; t < T; ++t) record(static_cast<long>(t), e.update(a + t * N, f + t * N));
#endif
            }
            return out.views();
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
