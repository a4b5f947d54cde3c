// pybind11 modules algid._core_v3 / _core_v4: the chain estimators of algid._core compiled for a
// wider instruction set (CMakeLists.txt sets the name, the -march level and module-local
// registration). algid/estimator.py imports the best one the CPU supports.
#include <pybind11/pybind11.h>

namespace py = pybind11;

void bind_chains_small(py::module_& m);
void bind_chains_medium(py::module_& m);
void bind_chains_large(py::module_& m);

PYBIND11_MODULE(ALGID_MODULE_NAME, m) {
  m.doc() = "algid C++ chain estimators built for " ALGID_MODULE_ISA;
  bind_chains_small(m);
  bind_chains_medium(m);
  bind_chains_large(m);
  m.attr("ISA") = ALGID_MODULE_ISA;
}
