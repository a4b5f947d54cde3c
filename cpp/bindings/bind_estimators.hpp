#pragma once
// The shared binding helpers: every estimator class of every instruction-set module is bound
// through bind_chain() / bind_continuous() below, which only convert arrays and release the GIL.
// The configuration structs are bound once, in algid._core (config.cpp), and shared by the
// instruction-set modules through pybind11's global type registry.
#include <algid/algid.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

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

/// An index in [0, size); an IndexError otherwise.
inline int require_index(int i, int size, const char* what) {
  if (i < 0 || i >= size)
    throw py::index_error(std::string(what) + " must be in 0.." + std::to_string(size - 1) + ", got " +
                          std::to_string(i));
  return i;
}

/// One estimator serves one thread at a time. run() releases the GIL, so without this another
/// thread could call into the same object while it runs and interleave the two records. A Busy
/// marks its object in use for the duration of a mutating call (constructed and destroyed with
/// the GIL held, so the registry needs no lock of its own); a second call on the same object
/// from another thread meanwhile raises RuntimeError (see idle()). Distinct objects never wait.
class Busy {
 public:
  explicit Busy(const void* object) : object_(object) {
    idle(object);
    registry().push_back(object);
  }
  ~Busy() {
    auto& objects = registry();
    objects.erase(std::find(objects.begin(), objects.end(), object_));
  }
  Busy(const Busy&) = delete;
  Busy& operator=(const Busy&) = delete;

  /// RuntimeError if `object` is in use by a call in another thread.
  static void idle(const void* object) {
    const auto& objects = registry();
    if (std::find(objects.begin(), objects.end(), object) != objects.end())
      throw std::runtime_error(
          "this estimator is in use by another thread (a run() is in progress): "
          "use one estimator per thread, or wait for the call to return");
  }

 private:
  static std::vector<const void*>& registry() {
    static std::vector<const void*> objects;
    return objects;
  }
  const void* object_;
};

/// `e` after checking that no other thread is running it (RuntimeError otherwise).
template <class Est>
const Est& idle(const Est& e) {
  Busy::idle(&e);
  return e;
}

/// Construct an estimator from its configuration, or raise ValueError with the reason.
template <class Est, class Error>
Est* make(const typename Est::Config& config, int n) {
  const Error e = Est::validate(config, n);
  if (e != Error::kNone) throw py::value_error(algid::to_string(e));
  return new Est(config, n);
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

/// What every estimator class exposes: its size, update(), samples and configuration.
template <class Est, class Class>
void bind_common(Class& cls) {
  cls.def_property_readonly("n", &Est::dofs)
      .def(
          "update",
          [](Est& e, const Array& accel, const Array& force) {
            require_sample(accel, force, e.dofs());
            const Busy busy(&e);
            return static_cast<int>(e.update(accel.data(), force.data()));
          },
          py::arg("accel"), py::arg("force"))
      .def_property_readonly("samples", [](const Est& e) { return idle(e).samples(); })
      .def_property_readonly("config", &Est::config);
}

/// ChainEstimator::record(), and with `full` histories (non-null pointers) the per-DOF extras.
template <class Est>
void record(Est& e, const double* accel, const double* force, long T, const algid::Histories<double>& histories,
            double* theta, double* instant, double* hadamard) {
  if (theta == nullptr) return e.record(accel, force, T, histories);
  const int n = e.dofs();
  e.run(accel, force, T, [&](long t, algid::Status s) {
    e.write_row(t, s, histories);
    for (int i = 0; i < n; ++i) {
      const auto th = e.theta(i), ti = e.theta_instant(i);
      std::copy(th.data(), th.data() + 4, theta + (t * n + i) * 4);
      std::copy(ti.data(), ti.data() + 4, instant + (t * n + i) * 4);
      hadamard[t * n + i] = e.hadamard(i);
    }
  });
}

/// Bind ChainEstimator<N> (N may be Dynamic) as `name`.
template <int N>
void bind_chain(py::module_& m, const char* name, bool module_local) {
  using Est = algid::ChainEstimator<N, double>;
  py::class_<Est> cls(m, name, "Algebraic estimator of an n-DOF chain (C++ core).", py::module_local(module_local));
  cls.def(py::init(&make<Est, algid::ConfigError>), py::arg("config"), py::arg("n"))
      .def_readonly_static("delay_samples", &Est::kDelay)
      .def_readonly_static("lanes", &Est::kLanes)
      .def("reseed",
           [](Est& e) {
             const Busy busy(&e);
             e.reseed();
           })
      .def_property_readonly("mass", [](const Est& e) { return Array(e.dofs(), idle(e).mass().data()); })
      .def_property_readonly("damping", [](const Est& e) { return Array(e.dofs(), idle(e).damping().data()); })
      .def_property_readonly("stiffness", [](const Est& e) { return Array(e.dofs() + 1, idle(e).stiffness().data()); })
      .def_property_readonly("valid",
                             [](const Est& e) {
                               idle(e);
                               py::array_t<bool> out(e.dofs());
                               std::copy(e.valid().data(), e.valid().data() + e.dofs(), out.mutable_data());
                               return out;
                             })
      .def_property_readonly("forced",
                             [](const Est& e) {
                               idle(e);
                               py::array_t<bool> out(e.dofs());
                               for (int i = 0; i < e.dofs(); ++i) out.mutable_data()[i] = e.forced(i);
                               return out;
                             })
      .def_property_readonly("window", [](const Est& e) { return idle(e).window(); })
      .def(
          "theta",
          [](const Est& e, int i) { return Array(4, idle(e).theta(require_index(i, e.dofs(), "dof")).data()); },
          py::arg("dof"))
      .def(
          "theta_instant",
          [](const Est& e, int i) { return Array(4, idle(e).theta_instant(require_index(i, e.dofs(), "dof")).data()); },
          py::arg("dof"))
      .def(
          "hadamard", [](const Est& e, int i) { return idle(e).hadamard(require_index(i, e.dofs(), "dof")); },
          py::arg("dof"))
      .def(
          "run",
          [](Est& e, const Array& accel, const Array& force, bool full) {
            const int n = e.dofs();
            require_record(accel, force, n);
            const py::ssize_t T = accel.shape(0);
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
            const algid::Histories<double> histories{out.int8("status"), out.f8("mass"), out.f8("damping"),
                                                     out.f8("stiffness"), out.boolean("valid")};
            double* theta = full ? out.f8("theta") : nullptr;
            double* instant = full ? out.f8("theta_instant") : nullptr;
            double* hadamard = full ? out.f8("hadamard") : nullptr;
            const Busy busy(&e);
            {
              py::gil_scoped_release release;
              record(e, accel.data(), force.data(), static_cast<long>(T), histories, theta, instant, hadamard);
            }
            return out.views();
          },
          py::arg("accel"), py::arg("force"), py::arg("full") = false,
          "Feed a whole record (T, n) in C++ with the GIL released; returns the estimate histories.");
  bind_common<Est>(cls);
}

/// What ContinuousEstimator::record() reports besides its histories, kept for numpy: the
/// change events and the window results.
template <class Est>
struct ContinuousLog {
  const Est& e;
  std::vector<typename Est::Event> events;
  std::vector<double> windows, variances, misfits;
  std::vector<std::int64_t> samples;

  void event(const typename Est::Event& ev) { events.push_back(ev); }
  void window(long sample) {
    windows.insert(windows.end(), e.last_window().data(), e.last_window().data() + e.params());
    variances.insert(variances.end(), e.last_variance().data(), e.last_variance().data() + e.params());
    samples.push_back(sample);
    misfits.push_back(e.last_misfit());
  }
};

/// A vector as a numpy array of `columns` columns (1: a vector).
template <class T>
py::array_t<T> to_numpy(const std::vector<T>& v, py::ssize_t columns = 1) {
  const py::ssize_t rows = static_cast<py::ssize_t>(v.size()) / columns;
  py::array_t<T> out = columns == 1 ? py::array_t<T>(rows) : py::array_t<T>({rows, columns});
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

/// ContinuousEstimator::record() of a whole record with the GIL released, as numpy arrays.
template <class Est>
py::dict run_continuous(Est& e, const Array& accel, const Array& force, long stride) {
  const int n = e.dofs(), P = e.params();
  require_record(accel, force, n);
  if (stride < 1) throw py::value_error("stride must be >= 1");
  const py::ssize_t T = accel.shape(0), rows = (T + stride - 1) / stride;
  py::array_t<std::int8_t> status(T);
  Array estimate({rows, static_cast<py::ssize_t>(P)}), sigma({rows, static_cast<py::ssize_t>(P)});
  py::array_t<std::int64_t> row_sample(rows);
  const algid::ContinuousHistories<double> histories{status.mutable_data(), estimate.mutable_data(),
                                                     sigma.mutable_data(), row_sample.mutable_data(), stride};
  ContinuousLog<Est> log{e, {}, {}, {}, {}, {}};
  const Busy busy(&e);
  {
    py::gil_scoped_release release;
    e.record(accel.data(), force.data(), static_cast<long>(T), histories, log);
  }
  const py::ssize_t E = static_cast<py::ssize_t>(log.events.size());
  py::array_t<std::int64_t> ev_sample(E), ev_param(E), ev_kind(E);
  Array ev_before(E), ev_after(E);
  for (py::ssize_t i = 0; i < E; ++i) {
    const auto& ev = log.events[static_cast<std::size_t>(i)];
    ev_sample.mutable_data()[i] = ev.sample;
    ev_param.mutable_data()[i] = ev.param;
    ev_kind.mutable_data()[i] = static_cast<int>(ev.kind);
    ev_before.mutable_data()[i] = ev.before;
    ev_after.mutable_data()[i] = ev.after;
  }
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
  out["windows"] = to_numpy(log.windows, P);
  out["window_sample"] = to_numpy(log.samples);
  out["window_variance"] = to_numpy(log.variances, P);
  out["window_misfit"] = to_numpy(log.misfits);
  return out;
}

/// Bind a ContinuousEstimator type `Est` (constructed from the Python ContinuousConfig,
/// ContinuousOptions) as `name`.
template <class Est, class Options>
void bind_continuous(py::module_& m, const char* name, bool module_local) {
  py::class_<Est> cls(m, name, "Continuous estimator of an n-DOF chain (C++ core).", py::module_local(module_local));
  cls.def(py::init([](const Options& o, int n) {
            return make<Est, algid::ContinuousConfigError>(o.template config<Est>(), n);
          }),
          py::arg("config"), py::arg("n"))
      .def_property_readonly("params", &Est::params)
      .def_readonly_static("capacity", &Est::kCapacity)
      .def_readonly_static("max_stagger", &Est::kMaxStagger)
      .def("reset",
           [](Est& e) {
             const Busy busy(&e);
             e.reset();
           })
      .def_property_readonly("estimate", [](const Est& e) { return Array(e.params(), idle(e).estimate().data()); })
      .def_property_readonly("sigma", [](const Est& e) { return Array(e.params(), idle(e).sigma().data()); })
      .def_property_readonly("last_window",
                             [](const Est& e) { return Array(e.params(), idle(e).last_window().data()); })
      .def_property_readonly("last_variance",
                             [](const Est& e) { return Array(e.params(), idle(e).last_variance().data()); })
      .def_property_readonly("hop_samples", &Est::hop_samples)
      .def_property_readonly("noise_rms",
                             [](const Est& e) {
                               idle(e);
                               Array out(2 * e.dofs());
                               for (int c = 0; c < 2 * e.dofs(); ++c) out.mutable_data()[c] = e.noise_rms(c);
                               return out;
                             })
      .def_property_readonly("ready", [](const Est& e) { return idle(e).ready(); })
      .def_property_readonly("window_results", [](const Est& e) { return idle(e).window_results(); })
      .def_property_readonly("dropout_samples", [](const Est& e) { return idle(e).dropout_samples(); })
      .def_property_readonly("dropout_runs", [](const Est& e) { return idle(e).dropout_runs(); })
      .def_property_readonly("last_dropout", [](const Est& e) { return idle(e).last_dropout(); })
      .def_property_readonly("dropout_channel", [](const Est& e) { return idle(e).dropout_channel(); })
      .def_property_readonly("screened_windows", [](const Est& e) { return idle(e).screened_windows(); })
      .def_property_readonly("last_misfit", [](const Est& e) { return idle(e).last_misfit(); })
      .def_property_readonly("window_samples", &Est::window_samples)
      .def_property_readonly("confirm", &Est::confirm)
      .def_property_readonly("budget", &Est::budget)
      .def_property_readonly("settle_samples", &Est::settle_samples)
      .def_property_readonly("prefilter_hz", &Est::prefilter_hz)
      .def_property_readonly("total_events", [](const Est& e) { return idle(e).total_events(); })
      .def("events",
           [](const Est& e) {
             idle(e);
             py::list out;
             for (int i = 0; i < e.events(); ++i) {
               const auto& ev = e.event(i);
               out.append(py::make_tuple(ev.sample, ev.param, static_cast<int>(ev.kind), ev.before, ev.after));
             }
             return out;
           })
      .def(
          "since_restart",
          [](const Est& e, int j) { return idle(e).since_restart(require_index(j, e.params(), "param")); },
          py::arg("param"))
      .def(
          "window_spread",
          [](const Est& e, int j) { return idle(e).window_spread(require_index(j, e.params(), "param")); },
          py::arg("param"))
      .def("run", &run_continuous<Est>, py::arg("accel"), py::arg("force"), py::arg("stride") = 1,
           "Feed a whole record (T, n) in C++ with the GIL released; returns histories and events.");
  cls.def_property_readonly("n", &Est::dofs)
      .def(
          "update",
          [](Est& e, const Array& accel, const Array& force) {
            require_sample(accel, force, e.dofs());
            const Busy busy(&e);
            return static_cast<int>(e.update(accel.data(), force.data()));
          },
          py::arg("accel"), py::arg("force"))
      .def_property_readonly("samples", [](const Est& e) { return idle(e).samples(); });
}

/// The chain sizes compiled as fixed-size instantiations (any other n runs the Dynamic one).
using FixedSizes = std::integer_sequence<int, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 16, 20, 32, 50, 64>;

/// The sizes of a sequence as a Python tuple.
template <int... Ns>
py::tuple sizes_tuple(std::integer_sequence<int, Ns...>) {
  return py::make_tuple(Ns...);
}

}  // namespace algid_bindings
