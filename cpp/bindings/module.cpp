// pybind11 modules algid._core, algid._core_v3 and algid._core_v4: the same source built for
// x86-64, x86-64-v3 (AVX2, FMA) and x86-64-v4 (AVX-512); CMakeLists.txt sets the module name
// and instruction set. Conversion only, no logic: the estimator classes come from the shared
// helpers in bind_estimators.hpp (chains.cpp, continuous.cpp), the configuration structs from
// config.cpp (in algid._core only; the other modules use them through pybind11's registry).
// algid/estimator.py imports the widest module the CPU runs.
// It includes neither the estimators nor the shared helpers: what it binds itself is small.
#include <algid/detail/cpu.hpp>

#include <pybind11/pybind11.h>

#include <string>

namespace py = pybind11;

namespace algid_bindings {
void bind_chain_classes(py::module_& m, bool module_local);
void bind_continuous_classes(py::module_& m, bool module_local);
void bind_config_classes(py::module_& m);
py::tuple chain_sizes();
}  // namespace algid_bindings

#ifndef ALGID_MODULE_NAME
#define ALGID_MODULE_NAME _core
#define ALGID_MODULE_ISA "x86-64"
#define ALGID_MODULE_BASE 1
#endif

PYBIND11_MODULE(ALGID_MODULE_NAME, m) {
  m.doc() = "algid C++ core built for " ALGID_MODULE_ISA ": on-line algebraic estimators of mass-spring-damper chains";
#ifdef ALGID_MODULE_BASE
  algid_bindings::bind_config_classes(m);
  m.def(
      "cpu_supports", [](const std::string& level) { return algid::detail::cpu_supports(level.c_str()); },
      py::arg("level"),
      "Whether this CPU (and OS) runs code built for `level`: 'x86-64-v3' (AVX2, FMA, BMI) or "
      "'x86-64-v4' (AVX-512 F/BW/CD/DQ/VL); False for other levels and architectures.");
  const bool module_local = false;
#else
  const bool module_local = true;  // the same C++ types are bound by the base module too
#endif
  algid_bindings::bind_chain_classes(m, module_local);
  algid_bindings::bind_continuous_classes(m, module_local);
  m.attr("SIZES") = algid_bindings::chain_sizes();
  m.attr("ISA") = ALGID_MODULE_ISA;
}
