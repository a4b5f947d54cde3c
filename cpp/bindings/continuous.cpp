// The continuous estimators of one extension module (see chains.cpp): the weak-form and the
// algebraic one, each run-time sized (Dynamic) for every n. Their per-sample work is that of
// their windows, whose weak-form buffers are run-time sized for every N, so fixed-size
// instantiations would add compile time to every install and no speed (docs/performance.md).
// ContinuousEstimatorDynamic(config, n) maps the run-time method of the Python config to the
// compiled type.
#include "bind_estimators.hpp"
#include "continuous_options.hpp"

namespace algid_bindings {

void bind_continuous_classes(py::module_& m, bool local) {
  bind_continuous<WeakFormContinuous, ContinuousOptions>(m, "WeakFormContinuousEstimatorDynamic", local);
  bind_continuous<AlgebraicContinuous, ContinuousOptions>(m, "AlgebraicContinuousEstimatorDynamic", local);
  m.def(
      "ContinuousEstimatorDynamic",
      [](const ContinuousOptions& o, int n) -> py::object {
        if (o.algebraic)
          return py::cast(make<AlgebraicContinuous, algid::ContinuousConfigError>(o.config<AlgebraicContinuous>(), n),
                          py::return_value_policy::take_ownership);
        return py::cast(make<WeakFormContinuous, algid::ContinuousConfigError>(o.config<WeakFormContinuous>(), n),
                        py::return_value_policy::take_ownership);
      },
      py::arg("config"), py::arg("n"),
      "The continuous estimator of the config's method: WeakFormContinuousEstimatorDynamic or "
      "AlgebraicContinuousEstimatorDynamic.");
}

}  // namespace algid_bindings
