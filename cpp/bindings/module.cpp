// pybind11 module algid._core: conversion only, no logic. The generic helper in
// bind_chain.hpp binds every fixed-size ChainEstimator<N>; the Python layer dispatches on n.
#include <algid/algid.hpp>
#include <algid/detail/cpu.hpp>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <string>

namespace py = pybind11;

void bind_continuous(pybind11::module_& m);  // continuous.cpp

void bind_chains_small(py::module_& m);
void bind_chains_medium(py::module_& m);
void bind_chains_large(py::module_& m);


PYBIND11_MODULE(_core, m) {
  m.doc() = "algid C++ core: on-line algebraic estimators of mass-spring-damper chains";
  bind_chains_small(m);
  bind_chains_medium(m);
  bind_chains_large(m);
  bind_continuous(m);
  m.attr("SIZES") = py::make_tuple(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 16, 20, 32, 50, 64);
  m.attr("ISA") = "x86-64";
  m.def(
      "cpu_supports", [](const std::string& level) { return algid::detail::cpu_supports(level.c_str()); },
      py::arg("level"),
      "Whether this CPU (and OS) runs code built for `level`: 'x86-64-v3' (AVX2, FMA, BMI) or "
      "'x86-64-v4' (AVX-512 F/BW/CD/DQ/VL); False for other levels and architectures.");
  py::enum_<algid::Status>(m, "Status")
      .value("OK", algid::Status::kOk)
      .value("WARMUP", algid::Status::kWarmup)
      .value("BAD_INPUT", algid::Status::kBadInput);
}
