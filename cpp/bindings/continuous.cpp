// pybind11 bindings of ContinuousEstimator<N>: conversion only, no logic. One generic helper
// binds every fixed-size instantiation; python/algid/continuous.py dispatches on n.
#include "bind_chain.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace {

using algid_bindings::Array;
using algid_bindings::require_record;
using algid_bindings::require_sample;

template <class Est>
py::tuple event_tuple(const typename Est::Event& ev) {
  return py::make_tuple(ev.sample, ev.param, static_cast<int>(ev.kind), ev.before, ev.after);
}

template <int N>
void bind_one(py::module_& m) {
  using Est = algid::ContinuousEstimator<N, double>;
  constexpr int kP = Est::kParams;
  const std::string name = "ContinuousEstimator" + std::to_string(N);
  py::class_<Est>(m, name.c_str(),
                  ("Continuous estimator of a " + std::to_string(N) + "-DOF chain (C++ core).").c_str())
      .def(py::init([](double dt, const std::string& boundary, double window_s, int stagger, int block, int confirm,
                       double step_threshold, double cusum_reference, double cusum_threshold, double cusum_clip,
                       double min_relative_spread, int min_windows, double overlap_efficiency, double horizon_s,
                       double prefilter_hz, int prefilter_order, bool detect, bool amortize, int min_samples,
                       double min_hadamard) {
             typename Est::Config c;
             c.dt = dt;
             c.boundary = algid_bindings::parse_boundary(boundary);
             c.window_s = window_s;
             c.stagger = stagger;
             c.block = block;
             c.confirm = confirm;
             c.step_threshold = step_threshold;
             c.cusum_reference = cusum_reference;
             c.cusum_threshold = cusum_threshold;
             c.cusum_clip = cusum_clip;
             c.min_relative_spread = min_relative_spread;
             c.min_windows = min_windows;
             c.overlap_efficiency = overlap_efficiency;
             c.horizon_s = horizon_s;
             c.prefilter_hz = prefilter_hz;
             c.prefilter_order = prefilter_order;
             c.detect = detect;
             c.amortize = amortize;
             c.validity.min_samples = min_samples;
             c.validity.min_hadamard = min_hadamard;
             const algid::ContinuousConfigError e = Est::validate(c);
             if (e != algid::ContinuousConfigError::kNone) throw py::value_error(algid::to_string(e));
             return std::make_unique<Est>(c);
           }),
           py::arg("dt"), py::arg("boundary"), py::arg("window_s"), py::arg("stagger"), py::arg("block"),
           py::arg("confirm"), py::arg("step_threshold"), py::arg("cusum_reference"), py::arg("cusum_threshold"),
           py::arg("cusum_clip"), py::arg("min_relative_spread"), py::arg("min_windows"),
           py::arg("overlap_efficiency"), py::arg("horizon_s"), py::arg("prefilter_hz"), py::arg("prefilter_order"),
           py::arg("detect"), py::arg("amortize"),
           py::arg("min_samples"), py::arg("min_hadamard"))
      .def_readonly_static("n", &Est::kDofs)
      .def_readonly_static("params", &Est::kParams)
      .def_readonly_static("capacity", &Est::kCapacity)
      .def_readonly_static("max_stagger", &Est::kMaxStagger)
      .def(
          "update",
          [](Est& e, const Array& accel, const Array& force) {
            require_sample(accel, force, N);
            return static_cast<int>(e.update(accel.data(), force.data()));
          },
          py::arg("accel"), py::arg("force"))
      .def("reset", &Est::reset)
      .def_property_readonly("estimate", [](const Est& e) { return Array(kP, e.estimate().data()); })
      .def_property_readonly("sigma", [](const Est& e) { return Array(kP, e.sigma().data()); })
      .def_property_readonly("last_window", [](const Est& e) { return Array(kP, e.last_window().data()); })
      .def_property_readonly("ready", &Est::ready)
      .def_property_readonly("samples", &Est::samples)
      .def_property_readonly("window_results", &Est::window_results)
      .def_property_readonly("window_samples", &Est::window_samples)
      .def_property_readonly("confirm", &Est::confirm)
      .def_property_readonly("budget", &Est::budget)
      .def_property_readonly("settle_samples", &Est::settle_samples)
      .def_property_readonly("prefilter_hz", &Est::prefilter_hz)
      .def_property_readonly("total_events", &Est::total_events)
      .def("events", [](const Est& e) {
        py::list out;
        for (int i = 0; i < e.events(); ++i) out.append(event_tuple<Est>(e.event(i)));
        return out;
      })
      .def("since_restart", [](const Est& e, int j) {
        if (j < 0 || j >= kP) throw py::index_error("parameter index out of range");
        return e.since_restart(j);
      }, py::arg("param"))
      .def("window_spread", [](const Est& e, int j) {
        if (j < 0 || j >= kP) throw py::index_error("parameter index out of range");
        return e.window_spread(j);
      }, py::arg("param"))
      .def(
          "run",
          [](Est& e, const Array& accel, const Array& force, long stride) {
            require_record(accel, force, N);
            if (stride < 1) throw py::value_error("stride must be >= 1");
            const py::ssize_t T = accel.shape(0);
            const py::ssize_t rows = (T + stride - 1) / stride;
            py::array_t<std::int8_t> status(T);
            Array estimate({rows, static_cast<py::ssize_t>(kP)}), sigma({rows, static_cast<py::ssize_t>(kP)});
            py::array_t<std::int64_t> row_sample(rows);
            std::vector<typename Est::Event> events;
            std::vector<double> windows;
            std::vector<std::int64_t> window_sample;
            const double* a = accel.data();
            const double* f = force.data();
            auto* st = status.mutable_data();
            double* pe = estimate.mutable_data();
            double* ps = sigma.mutable_data();
            auto* pr = row_sample.mutable_data();
            const long first = e.samples();
            {
              py::gil_scoped_release release;
              py::ssize_t row = 0;
              for (py::ssize_t t = 0; t < T; ++t) {
                const long results = e.window_results();
                st[t] = static_cast<std::int8_t>(e.update(a + t * N, f + t * N));
                for (int i = 0; i < e.events(); ++i) events.push_back(e.event(i));
                if (e.window_results() != results) {
                  windows.insert(windows.end(), e.last_window().data(), e.last_window().data() + kP);
                  window_sample.push_back(first + t);
                }
                if (t % stride == 0) {
                  for (int j = 0; j < kP; ++j) {
                    pe[row * kP + j] = e.estimate()(j);
                    ps[row * kP + j] = e.sigma()(j);
                  }
                  pr[row] = first + t;
                  ++row;
                }
              }
            }
            const py::ssize_t E = static_cast<py::ssize_t>(events.size());
            py::array_t<std::int64_t> ev_sample(E), ev_param(E), ev_kind(E);
            Array ev_before(E), ev_after(E);
            for (py::ssize_t i = 0; i < E; ++i) {
              const auto& ev = events[static_cast<std::size_t>(i)];
              ev_sample.mutable_data()[i] = ev.sample;
              ev_param.mutable_data()[i] = ev.param;
              ev_kind.mutable_data()[i] = static_cast<int>(ev.kind);
              ev_before.mutable_data()[i] = ev.before;
              ev_after.mutable_data()[i] = ev.after;
            }
            const py::ssize_t R = static_cast<py::ssize_t>(window_sample.size());
            Array win({R, static_cast<py::ssize_t>(kP)});
            std::copy(windows.begin(), windows.end(), win.mutable_data());
            py::array_t<std::int64_t> win_sample(R);
            std::copy(window_sample.begin(), window_sample.end(), win_sample.mutable_data());
            py::dict out;
            out["status"] = status;
            out["estimate"] = estimate;
            out["sigma"] = sigma;
            out["sample"] = row_sample;
            out["event_sample"] = ev_sample;
            out["event_param"] = ev_param;
            out["event_kind"] = ev_kind;
            out["event_before"] = ev_before;
            out["event_after"] = ev_after;
            out["windows"] = win;
            out["window_sample"] = win_sample;
            return out;
          },
          py::arg("accel"), py::arg("force"), py::arg("stride") = 1,
          "Feed a whole record (T, n) in C++ with the GIL released; returns histories and events.");
}

template <int... Ns>
void bind_sizes(py::module_& m, std::integer_sequence<int, Ns...>) {
  (bind_one<Ns>(m), ...);
}

}  // namespace

void bind_continuous(py::module_& m) {
  bind_sizes(m, std::integer_sequence<int, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 16, 20, 32, 50, 64>{});
  py::enum_<algid::ChangeKind>(m, "ChangeKind")
      .value("NONE", algid::ChangeKind::kNone)
      .value("STEP", algid::ChangeKind::kStep)
      .value("DRIFT", algid::ChangeKind::kDrift);
}
