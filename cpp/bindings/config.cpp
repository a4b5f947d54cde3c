// The configuration structs and enums, bound once in algid._core and used by every
// instruction-set module (pybind11's global type registry): the defaults live in C++ only.
#include "bind_estimators.hpp"

#include <sstream>
#include <string>

namespace algid_bindings {

namespace {

algid::Boundary parse_boundary(const std::string& b) {
  if (b == "fixed") return algid::Boundary::kFixed;
  if (b == "free") return algid::Boundary::kFree;
  throw py::value_error("boundary must be 'fixed' or 'free', got '" + b + "'");
}

const char* boundary_name(algid::Boundary b) { return b == algid::Boundary::kFree ? "free" : "fixed"; }

algid::WindowMethod parse_method(const std::string& m) {
  if (m == "weak_form") return algid::WindowMethod::kWeakForm;
  if (m == "algebraic") return algid::WindowMethod::kAlgebraic;
  throw py::value_error("method must be 'weak_form' or 'algebraic', got '" + m + "'");
}

const char* method_name(algid::WindowMethod m) {
  return m == algid::WindowMethod::kAlgebraic ? "algebraic" : "weak_form";
}

// dt, boundary (as "fixed" / "free") and the validity rule, which both configs carry.
template <class Config, class Class>
void bind_window_fields(Class& cls) {
  cls.def_readwrite("dt", &Config::dt, "sample period [s]")
      .def_property(
          "boundary", [](const Config& c) { return boundary_name(c.boundary); },
          [](Config& c, const std::string& b) { c.boundary = parse_boundary(b); },
          "right end: 'fixed' (a wall, k_{n+1} identified) or 'free' (k_{n+1} = 0)")
      .def_property(
          "min_samples", [](const Config& c) { return c.validity.min_samples; },
          [](Config& c, int v) { c.validity.min_samples = v; }, "samples since t0 before a solution is trusted")
      .def_property(
          "min_hadamard", [](const Config& c) { return c.validity.min_hadamard; },
          [](Config& c, double v) { c.validity.min_hadamard = v; },
          "lowest doubly equilibrated Hadamard ratio of a trusted system, in [0, 1)");
}

}  // namespace

void bind_config_classes(py::module_& m) {
  py::enum_<algid::Status>(m, "Status")
      .value("OK", algid::Status::kOk)
      .value("WARMUP", algid::Status::kWarmup)
      .value("BAD_INPUT", algid::Status::kBadInput)
      .value("DROPOUT", algid::Status::kDropout);
  py::enum_<algid::Dropout>(m, "Dropout")
      .value("NONE", algid::Dropout::kNone)
      .value("STUCK", algid::Dropout::kStuck)
      .value("CLIPPED", algid::Dropout::kClipped);
  py::enum_<algid::ChangeKind>(m, "ChangeKind")
      .value("NONE", algid::ChangeKind::kNone)
      .value("STEP", algid::ChangeKind::kStep)
      .value("DRIFT", algid::ChangeKind::kDrift);

  using Chain = algid::ChainConfig<double>;
  py::class_<Chain> chain(m, "ChainConfig", "Configuration of a ChainEstimator (C++ ChainConfig; defaults from C++).");
  chain.def(py::init<>());
  bind_window_fields<Chain>(chain);
  chain.def(
      "validate", [](const Chain& c, int n) { return std::string(algid::to_string(algid::validate(c, n))); },
      py::arg("n"), "'ok', or why a chain of n DOF rejects this configuration");

  using Cont = algid::ContinuousConfig<double>;
  py::class_<Cont> cont(m, "ContinuousConfig",
                        "Configuration of a ContinuousEstimator (C++ ContinuousConfig; defaults from C++).");
  cont.def(py::init<>());
  bind_window_fields<Cont>(cont);
  cont.def_property(
          "method", [](const Cont& c) { return method_name(c.method); },
          [](Cont& c, const std::string& v) { c.method = parse_method(v); },
          "window results: 'weak_form' (GLS over all test-function rows, bias-compensated) or 'algebraic'")
      .def_readwrite("window_s", &Cont::window_s, "window length L [s]; -1: 0.5 (weak form), 0.3 (algebraic)")
      .def_readwrite("stagger", &Cont::stagger, "windows in flight K, started L/K apart")
      .def_readwrite("block", &Cont::block, "window results per block median")
      .def_readwrite("confirm", &Cont::confirm, "window results in the step test; 0: 2K+1")
      .def_readwrite("step_threshold", &Cont::step_threshold, "step test: |median z| above this")
      .def_readwrite("cusum_reference", &Cont::cusum_reference, "drift test: CUSUM reference [block-median sigmas]")
      .def_readwrite("cusum_threshold", &Cont::cusum_threshold, "drift test: alarm level [block-median sigmas]")
      .def_readwrite("cusum_clip", &Cont::cusum_clip, "drift test: clip of one standardised block median")
      .def_readwrite("min_relative_spread", &Cont::min_relative_spread,
                     "floor of the per-window spread relative to |estimate|")
      .def_readwrite("min_windows", &Cont::min_windows, "window results since a restart before the tests are armed")
      .def_readwrite("overlap_efficiency", &Cont::overlap_efficiency,
                     "independent fraction of the staggered window results, (0, 1]")
      .def_readwrite("horizon_s", &Cont::horizon_s, "forgetting time constant of the block mean [s]; 0: none")
      .def_readwrite("prefilter_hz", &Cont::prefilter_hz,
                     "low-pass on accelerations and forces [Hz]; -1: 0.05/dt, 0: off")
      .def_readwrite("prefilter_order", &Cont::prefilter_order, "Butterworth order of the prefilter: 2 or 4")
      .def_readwrite("band_hz", &Cont::band_hz, "weak form: highest test-function frequency [Hz]; -1: 0.05/dt")
      .def_readwrite("accel_noise", &Cont::accel_noise, "weak form: acceleration noise RMS [m/s^2]; -1: estimated")
      .def_readwrite("force_noise", &Cont::force_noise, "weak form: force noise RMS [N]; -1: estimated")
      .def_readwrite("bias_compensation", &Cont::bias_compensation,
                     "weak form: subtract the regressor-noise term of the normal equations")
      .def_readwrite("joint_efficiency", &Cont::joint_efficiency,
                     "weak form: sigma = sqrt(diag(N^-1) / joint_efficiency) (overlap of the windows' information)")
      .def_readwrite(
          "long_window_s", &Cont::long_window_s,
          "weak form: length of a second, longer set of windows with a joint sum of its own [s] (each "
          "parameter reported from the joint sum with the smaller uncertainty); -1: three times window_s, 0: none")
      .def_readwrite("gls", &Cont::gls, "weak form: rows weighted by their noise covariance (False: unweighted)")
      .def_readwrite("joint", &Cont::joint,
                     "weak form: estimate from the summed window normal equations (False: block medians)")
      .def_readwrite("detect", &Cont::detect, "run the change detector")
      .def_readwrite("amortize", &Cont::amortize, "spread the per-parameter work over the samples")
      .def_readwrite("outlier_ratio", &Cont::outlier_ratio,
                     "a sample beyond this many times its channel's running RMS is bad input; 0: off")
      .def_readwrite("misfit_ratio", &Cont::misfit_ratio,
                     "weak form: a window whose misfit exceeds this many times the median of the 16 before "
                     "(or 1) stays out of the joint estimate; 0: off")
      .def_readwrite("stuck_samples", &Cont::stuck_samples,
                     "an acceleration repeating one value this many samples is a dropout; 0: off")
      .def_readwrite("clip_samples", &Cont::clip_samples,
                     "an acceleration repeating its largest or smallest value this many samples is clipped; 0: off");
  cont.def(
      "validate",
      [](const Cont& c, int n) {
        return std::string(algid::to_string(algid::ContinuousEstimator<algid::Dynamic, double>::validate(c, n)));
      },
      py::arg("n"), "'ok', or why a chain of n DOF rejects this configuration");
}

}  // namespace algid_bindings
