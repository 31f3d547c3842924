// The Python class of a model, written once (engine/bindings/python): Filter wraps one engine
// with the mutex that serialises the calls on it; the configuration comes from a dict and keyword
// arguments through the model's field table; BindFilter() binds what every model's class has
// (the constructor, steps, config, poses, trajectories, summary, checkpoint, resume, repr and
// pickling through grove._restore). A model's file binds only its own inputs and read-outs.
//
// Thread safety: each Python object wraps one engine and a mutex; every call locks it with the
// GIL released, so calls on one object serialise and calls on two objects run in parallel. The
// rule that keeps this free of deadlocks: no thread waits for an object's mutex while it holds
// the GIL (Locked() releases the GIL first), so a thread holding the mutex may take the GIL.
// The configuration is copied at construction and never changes, so reading it needs no lock.
#ifndef GROVE_ENGINE_BINDINGS_PYTHON_FILTER_BINDING_H_
#define GROVE_ENGINE_BINDINGS_PYTHON_FILTER_BINDING_H_

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "engine/bindings/python/python_values.h"
#include "grove/config_fields.h"
#include "grove/config_json.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove::python {

// Applies the keys of `mapping` to `config`: InvalidArgument naming an unknown key (with the
// nearest known one) or a bad value. Checks each value, not the rules between fields.
template <typename Config>
Status ApplyPythonConfig(const std::vector<ConfigField<Config>>& fields, const py::dict& mapping,
                         Config* config) {
  for (auto [key, value] : mapping) {
    if (!PyUnicode_Check(key.ptr())) {
      return InvalidArgumentError("configuration keys must be strings, found " + TypeName(key));
    }
    const std::string name = py::cast<std::string>(key);
    const ConfigField<Config>* field = FindField(fields, name);
    if (field == nullptr) {
      std::vector<std::string> known;
      for (const ConfigField<Config>& f : fields) known.push_back(f.info.name);
      const std::string nearest = NearestKey(name, known);
      return InvalidArgumentError("unknown key " + QuoteForMessage(name) +
                                  (nearest.empty() ? "" : " (did you mean \"" + nearest + "\"?)"));
    }
    StatusOr<FieldValue> v = FieldValueFromPython(field->info, value);
    if (!v.ok()) return v.status();
    field->set(config, *v);
  }
  return Status::Ok();
}

// The configuration from a mapping (or None) and keyword arguments (which win over the mapping),
// validated; raises InvalidArgumentError.
template <typename Config>
Config MakeConfig(const std::vector<ConfigField<Config>>& fields, const py::object& config,
                  const py::kwargs& kwargs) {
  Config result;
  if (!config.is_none()) {
    const bool mapping =
        PyDict_Check(config.ptr()) ||
        py::isinstance(config, py::module_::import("collections.abc").attr("Mapping"));
    if (!mapping) {
      std::string hint;
      if (PyUnicode_Check(config.ptr()) || PyBytes_Check(config.ptr())) {
        hint = " (for JSON text, pass json.loads(text))";
      }
      throw py::type_error("config must be a dict of configuration keys, not " + TypeName(config) +
                           hint);
    }
    ThrowIfError(ApplyPythonConfig(fields, py::dict(config), &result));
  }
  ThrowIfError(ApplyPythonConfig(fields, py::dict(kwargs), &result));
  ThrowIfError(result.Validate());
  return result;
}

template <typename Config>
py::dict ConfigToDict(const std::vector<ConfigField<Config>>& fields, const Config& config) {
  py::dict out;
  for (const ConfigField<Config>& f : fields) {
    out[f.info.name] = FieldValueToPython(f.info, f.get(config));
  }
  return out;
}

// "grove.FootSlam(particles=3000, seed=1, threads=1)": particles, seed and every field that
// differs from its default, as keyword arguments that rebuild the configuration.
template <typename Config>
std::string ConfigRepr(const char* type, const std::vector<ConfigField<Config>>& fields,
                       const Config& config) {
  const Config defaults;
  std::string out = std::string("grove.") + type + "(";
  bool first = true;
  for (const ConfigField<Config>& f : fields) {
    const std::string value = FormatFieldValue(f.info, f.get(config));
    const std::string name = f.info.name;
    if (name != "particles" && name != "seed" &&
        value == FormatFieldValue(f.info, f.get(defaults))) {
      continue;
    }
    out += (first ? "" : ", ") + name + "=" +
           (f.info.type == FieldType::kChoice ? "'" + value + "'" : value);
    first = false;
  }
  return out + ")";
}

// The configuration table as a list of dicts: name, type, help, changes_results, default and
// the range (min, max, min_open, max_open) or the choices.
template <typename Config>
py::list FieldsToList(const std::vector<ConfigField<Config>>& fields) {
  static const char* const kTypeNames[] = {"integer", "unsigned", "real", "choice"};
  const Config defaults;
  py::list out;
  for (const ConfigField<Config>& f : fields) {
    py::dict d;
    d["name"] = f.info.name;
    d["type"] = kTypeNames[static_cast<int>(f.info.type)];
    d["help"] = f.info.help;
    d["changes_results"] = f.info.effect == kChangesResults;
    d["default"] = FieldValueToPython(f.info, f.get(defaults));
    switch (f.info.type) {
      case FieldType::kInteger:
        d["min"] = f.info.min_integer;
        d["max"] = f.info.max_integer;
        break;
      case FieldType::kUnsigned:
        d["min"] = 0;
        d["max"] = UINT64_MAX;
        break;
      case FieldType::kReal:
        d["min"] = f.info.interval.min;
        d["max"] = f.info.interval.max;
        d["min_open"] = f.info.interval.min_open;
        d["max_open"] = f.info.interval.max_open;
        break;
      case FieldType::kChoice:
        d["choices"] = f.info.choices;
        break;
    }
    out.append(d);
  }
  return out;
}
// One engine and the mutex that serialises the calls on it.
template <typename Engine, typename Config>
class Filter {
 public:
  Filter(std::unique_ptr<Engine> engine, const Config& config, std::string user_data)
      : engine_(std::move(engine)), config_(config), user_data_(std::move(user_data)) {}

  // Runs f(engine) with the GIL released and the mutex held; returns its result, which must
  // not be a Python object.
  template <typename F>
  auto Locked(F&& f) const {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mu_);
    return f(*engine_);
  }

  const Config& config() const { return config_; }
  const std::string& user_data() const { return user_data_; }

 private:
  std::unique_ptr<Engine> engine_;
  mutable std::mutex mu_;
  const Config config_;
  const std::string user_data_;
};

template <typename Engine, typename Config>
std::unique_ptr<Filter<Engine, Config>> CreateFilter(const Config& config) {
  StatusOr<std::unique_ptr<Engine>> engine = [&] {
    py::gil_scoped_release release;
    return Engine::Create(config);
  }();
  return std::make_unique<Filter<Engine, Config>>(ValueOrRaise(std::move(engine)), config, "");
}

template <typename Engine, typename Config>
std::unique_ptr<Filter<Engine, Config>> ResumeFilter(const Config& config, py::bytes data) {
  std::string bytes = data;  // a copy: the engine reads it with the GIL released
  std::string user_data;
  StatusOr<std::unique_ptr<Engine>> engine = [&] {
    py::gil_scoped_release release;
    return Engine::Resume(config, bytes, "checkpoint", &user_data);
  }();
  return std::make_unique<Filter<Engine, Config>>(ValueOrRaise(std::move(engine)), config,
                                                  std::move(user_data));
}

// What pickle and copy need, at every protocol: a module-level function and its arguments
// (protocols 0 and 1 cannot rebuild a pybind11 object from its class and a state).
template <typename Engine, typename Config>
py::tuple Reduce(const Filter<Engine, Config>& f, const char* name,
                 const std::vector<ConfigField<Config>>& fields) {
  std::string data = ValueOrRaise(f.Locked([](Engine& e) { return e.Checkpoint(); }));
  return py::make_tuple(
      py::module_::import("grove").attr("_restore"),
      py::make_tuple(py::str(name), ConfigToDict(fields, f.config()), py::bytes(data)));
}

// Runs step(engine, k) -> Status for the rows k = 0 .. n - 1 with the GIL released, in one
// locked call: the first failing row's error is raised, its message prefixed by context(k);
// Ctrl-C stops between rows (KeyboardInterrupt). The rows before stay applied.
template <typename Engine, typename Config, typename Step, typename Context>
void RunRows(const Filter<Engine, Config>& f, size_t n, Step&& step, Context&& context) {
  size_t failed_row = n;
  bool interrupted = false;
  Status status = f.Locked([&](Engine& e) {
    SignalPoller poller;
    for (size_t k = 0; k < n; ++k) {
      Status s = step(e, k);
      if (!s.ok()) {
        failed_row = k;
        return s;
      }
      if (!poller.Ok()) {
        interrupted = true;
        break;
      }
    }
    return Status::Ok();
  });
  if (interrupted) throw py::error_already_set();
  if (!status.ok()) Raise(status, context(failed_row));
}

// The class `name` of a model's filter in `m`, with what every model's class has: the
// constructor (a config dict and keyword arguments, checked against `fields`), steps, config,
// user_data, config_fields, mean_pose, heaviest_pose, mean_trajectory, summary (the facade's
// summary as summary_dict(summary) makes it, with 'report'), checkpoint, resume, repr and
// pickling; heaviest_trajectory, set_start_time and check_invariants when the engine has them. The
// caller adds the model's own methods to the class returned. `doc` is the class's docstring, to
// which the thread rules are added.
template <typename Engine, typename Config, typename SummaryDict>
py::class_<Filter<Engine, Config>> BindFilter(py::module_& m, const char* name,
                                              const std::string& doc,
                                              const std::vector<ConfigField<Config>>* fields,
                                              SummaryDict summary_dict) {
  using F = Filter<Engine, Config>;
  py::class_<F> cls(m, name, (doc + kThreadRules).c_str());
  cls.def(py::init([fields](const py::object& config, const py::kwargs& kwargs) {
            return CreateFilter<Engine>(MakeConfig(*fields, config, kwargs));
          }),
          py::arg("config") = py::none())
      .def_property_readonly(
          "steps", [](const F& f) { return f.Locked([](Engine& e) { return e.steps(); }); },
          "Filter steps so far.")
      .def_property_readonly(
          "config", [fields](const F& f) { return ConfigToDict(*fields, f.config()); },
          "The effective configuration as a dict, every key (a new dict each time).")
      .def_property_readonly(
          "user_data", [](const F& f) { return py::bytes(f.user_data()); },
          "The user data stored in the checkpoint this filter was resumed from (b'' otherwise).")
      .def_static(
          "config_fields", [fields]() { return FieldsToList(*fields); },
          "The configuration table: one dict per key (name, type, help, changes_results, "
          "default, and min/max or choices), in the order of the C++ struct.")
      .def(
          "mean_pose",
          [](const F& f) { return PoseTuple(f.Locked([](Engine& e) { return e.MeanPose(); })); },
          "The weighted mean pose after the last step: grove.Pose(x, y, heading), metres and "
          "radians.")
      .def(
          "heaviest_pose",
          [](const F& f) {
            return PoseTuple(f.Locked([](Engine& e) { return e.HeaviestPose(); }));
          },
          "The heaviest particle's current pose: grove.Pose(x, y, heading).")
      .def(
          "mean_trajectory",
          [](const F& f) {
            return TrajectoryArray(
                f.Locked([](Engine& e) { return std::vector<StampedPose>(e.MeanTrajectory()); }));
          },
          "The weighted mean pose at the start and after every step: a new float64 array of "
          "shape (n, 4), columns t, x, y, heading.")
      .def(
          "summary",
          [summary_dict](const F& f) {
            const auto summary = f.Locked([](Engine& e) { return e.Summary(); });
            py::dict d = summary_dict(summary);
            d["report"] = summary.BriefReport();
            return d;
          },
          "What the run asked for, used and cost, as a dict; 'report' is the one-paragraph "
          "summary the grove command prints.")
      .def(
          "checkpoint",
          [](const F& f, py::bytes user_data) {
            std::string data = user_data;
            return py::bytes(ValueOrRaise(f.Locked([&](Engine& e) { return e.Checkpoint(data); })));
          },
          py::arg("user_data") = py::bytes(),
          "The whole state after the last step as checkpoint bytes (the sharing between the "
          "particles kept). `user_data` is stored as is; resume() gives it back as user_data. "
          "Raises FailedPreconditionError after an error stopped the filter.")
      .def_static(
          "resume",
          [fields](py::bytes data, const py::object& config, const py::kwargs& kwargs) {
            return ResumeFilter<Engine>(MakeConfig(*fields, config, kwargs), data);
          },
          py::arg("data"), py::arg("config") = py::none(),
          "A filter continuing from checkpoint bytes made by checkpoint() under a configuration "
          "equal in every field but threads and batch (give it as to the constructor). Stepping "
          "it gives, bit for bit, what the checkpointed filter would have given. Raises "
          "DataLossError for corrupt bytes and FailedPreconditionError for a different "
          "configuration (naming the field).")
      .def("__repr__", [name, fields](const F& f) { return ConfigRepr(name, *fields, f.config()); })
      .def(
          "__reduce_ex__",
          [name, fields](const F& f, int /*protocol*/) { return Reduce(f, name, *fields); },
          py::arg("protocol"),
          "Pickling at every protocol: grove._restore(class name, config, checkpoint bytes).")
      .def("__reduce__", [name, fields](const F& f) { return Reduce(f, name, *fields); })
      .def(py::pickle(
          [fields](const F& f) {
            std::string data = ValueOrRaise(f.Locked([](Engine& e) { return e.Checkpoint(); }));
            return py::make_tuple(ConfigToDict(*fields, f.config()), py::bytes(data));
          },
          [fields](const py::tuple& state) {
            if (state.size() != 2) RaiseInvalid("pickled filter: expected (config, checkpoint)");
            Config config = MakeConfig(*fields, state[0], py::kwargs());
            return ResumeFilter<Engine, Config>(config, state[1].cast<py::bytes>());
          }));
  if constexpr (requires(const Engine& e) { e.HeaviestTrajectory(); }) {
    cls.def(
        "heaviest_trajectory",
        [](const F& f) {
          return TrajectoryArray(
              ValueOrRaise(f.Locked([](Engine& e) { return e.HeaviestTrajectory(); })));
        },
        "The heaviest particle's path traced through its ancestry, at the times of "
        "mean_trajectory(): a new float64 array of shape (n, 4), columns t, x, y, heading.");
  }
  if constexpr (requires(Engine & e) { e.SetStartTime(0.0); }) {
    cls.def(
        "set_start_time",
        [](const F& f, double t) {
          ThrowIfError(f.Locked([&](Engine& e) { return e.SetStartTime(t); }));
        },
        py::arg("t"),
        "Sets the time of the start (the first step must come after it); without it the start "
        "takes the first step's time. FailedPreconditionError after the first step.");
  }
  if constexpr (requires(const Engine& e) { e.CheckInvariants(); }) {
    cls.def(
        "check_invariants",
        [](const F& f) { ThrowIfError(f.Locked([](Engine& e) { return e.CheckInvariants(); })); },
        "Walks the whole shared state and checks every reference count; raises InternalError "
        "naming a broken rule. Slow; for tests.");
  }
  return cls;
}

}  // namespace grove::python

#endif  // GROVE_ENGINE_BINDINGS_PYTHON_FILTER_BINDING_H_
