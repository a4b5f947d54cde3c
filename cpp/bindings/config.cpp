// The configuration structs and enums, bound once in algid._core and used by every
// instruction-set module (pybind11's global type registry): the defaults live in C++ only.
#include "bind_estimators.hpp"
#include "continuous_options.hpp"

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

// A field of both estimators' configurations: read from the weak form's, written to both.
#define ALGID_BOTH(field, doc)                               \
  def_property(                                              \
      #field, [](const Options& o) { return o.weak.field; }, \
      [](Options& o, decltype(o.weak.field) v) { o.weak.field = o.algebraic_config.field = v; }, doc)
// A field of one estimator's configuration (`weak` or `algebraic_config`).
#define ALGID_ONE(config, field, doc)                          \
  def_property(                                                \
      #field, [](const Options& o) { return o.config.field; }, \
      [](Options& o, decltype(o.config.field) v) { o.config.field = v; }, doc)

void bind_continuous_options(py::module_& m) {
  using Options = ContinuousOptions;
  py::class_<Options> cont(m, "ContinuousConfig",
                           "Configuration of a ContinuousEstimator: the window method and the fields of its two C++ "
                           "configurations (defaults from C++).");
  cont.def(py::init<>())
      .def_property(
          "method", [](const Options& o) { return o.algebraic ? "algebraic" : "weak_form"; },
          [](Options& o, const std::string& v) {
            if (v != "weak_form" && v != "algebraic")
              throw py::value_error("method must be 'weak_form' or 'algebraic', got '" + v + "'");
            o.algebraic = v == "algebraic";
          },
          "window results: 'weak_form' (WeakFormSource: GLS over all test-function rows, bias-compensated) or "
          "'algebraic' (AlgebraicWindows: the paper's windows behind a prefilter)")
      .ALGID_BOTH(dt, "sample period [s]")
      .def_property(
          "boundary", [](const Options& o) { return boundary_name(o.weak.boundary); },
          [](Options& o, const std::string& b) { o.weak.boundary = o.algebraic_config.boundary = parse_boundary(b); },
          "right end: 'fixed' (a wall, k_{n+1} identified) or 'free' (k_{n+1} = 0)")
      .def_property(
          "min_samples", [](const Options& o) { return o.algebraic_config.validity.min_samples; },
          [](Options& o, int v) { o.algebraic_config.validity.min_samples = v; },
          "algebraic: samples since t0 before a window's solution is trusted")
      .def_property(
          "min_hadamard", [](const Options& o) { return o.algebraic_config.validity.min_hadamard; },
          [](Options& o, double v) { o.algebraic_config.validity.min_hadamard = v; },
          "algebraic: lowest doubly equilibrated Hadamard ratio of a trusted system, in [0, 1)")
      .def_readwrite("window_s", &Options::window_s, "window length L [s]; -1: 0.5 (weak form), 0.3 (algebraic)")
      .def_readwrite(
          "overlap_efficiency", &Options::overlap_efficiency,
          "independent fraction of the staggered window results, (0, 1]; -1: 0.25 (weak form), 0.5 (algebraic)")
      .ALGID_BOTH(stagger, "windows in flight K, started L/K apart")
      .ALGID_BOTH(block, "window results per block median")
      .ALGID_BOTH(confirm, "window results in the step test; 0: 2K+1")
      .ALGID_BOTH(step_threshold, "step test: |median z| above this")
      .ALGID_BOTH(cusum_reference, "drift test: CUSUM reference [block-median sigmas]")
      .ALGID_BOTH(cusum_threshold, "drift test: alarm level [block-median sigmas]")
      .ALGID_BOTH(cusum_clip, "drift test: clip of one standardised block median")
      .ALGID_BOTH(min_relative_spread, "floor of the per-window spread relative to |estimate|")
      .ALGID_BOTH(min_windows, "window results since a restart before the tests are armed")
      .ALGID_BOTH(horizon_s, "forgetting time constant of the block mean [s]; 0: none")
      .ALGID_ONE(algebraic_config, prefilter_hz,
                 "algebraic: low-pass on accelerations and forces [Hz]; -1: 0.05/dt, 0: off")
      .ALGID_ONE(algebraic_config, prefilter_order, "algebraic: Butterworth order of the prefilter: 2 or 4")
      .ALGID_ONE(weak, band_hz, "weak form: highest test-function frequency [Hz]; -1: 0.05/dt")
      .ALGID_ONE(weak, accel_noise, "weak form: acceleration noise RMS [m/s^2]; -1: estimated")
      .ALGID_ONE(weak, force_noise, "weak form: force noise RMS [N]; -1: estimated")
      .ALGID_ONE(weak, bias_compensation, "weak form: subtract the regressor-noise term of the normal equations")
      .ALGID_ONE(weak, joint_efficiency,
                 "weak form: sigma = sqrt(diag(N^-1) / joint_efficiency) (overlap of the windows' information)")
      .ALGID_ONE(
          weak, long_window_s,
          "weak form: length of a second, longer set of windows with a joint sum of its own [s] (each "
          "parameter reported from the joint sum with the smaller uncertainty); -1: three times window_s, 0: none")
      .ALGID_ONE(weak, gls, "weak form: rows weighted by their noise covariance (False: unweighted)")
      .ALGID_ONE(weak, joint, "weak form: estimate from the summed window normal equations (False: block medians)")
      .ALGID_BOTH(detect, "run the change detector")
      .ALGID_BOTH(amortize, "spread the per-parameter work over the samples")
      .ALGID_BOTH(outlier_ratio, "a sample beyond this many times its channel's running RMS is bad input; 0: off")
      .ALGID_ONE(weak, misfit_ratio,
                 "weak form: a window whose misfit exceeds this many times the median of the 16 before "
                 "(or 1) stays out of the joint estimate; 0: off")
      .ALGID_BOTH(stuck_samples, "an acceleration repeating one value this many samples is a dropout; 0: off")
      .ALGID_BOTH(clip_samples,
                  "an acceleration repeating its largest or smallest value this many samples is clipped; 0: off");
  cont.def("validate", &Options::validate, py::arg("n"), "'ok', or why a chain of n DOF rejects this configuration");
}

#undef ALGID_BOTH
#undef ALGID_ONE

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

  bind_continuous_options(m);
}

}  // namespace algid_bindings
