// The `grove` Python module: FootSLAM and landmark FastSLAM for Python, over the public headers
// alone (grove/footslam.h, grove/fastslam.h and the configuration tables' helpers).
//
// Thread safety: each Python object wraps one engine and a mutex; every call locks it with the
// GIL released, so calls on one object serialise and calls on two objects run in parallel. The
// rule that keeps this free of deadlocks: no thread waits for an object's mutex while it holds
// the GIL (Locked() releases the GIL first), so a thread holding the mutex may take the GIL.
// The configuration is copied at construction and never changes, so reading it needs no lock.
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "grove/config_fields.h"
#include "grove/config_json.h"
#include "grove/fastslam.h"
#include "grove/footslam.h"
#include "grove/status.h"
#include "grove/types.h"
#include "grove/version.h"

namespace grove::python {
namespace {

namespace py = pybind11;

// ---- Errors ----

// The exception classes, one per status code, all subclasses of GroveError. They live for the
// whole process (a module is never unloaded), so they are never released.
PyObject* g_grove_error = nullptr;
PyObject* g_errors[static_cast<int>(StatusCode::kInternal) + 1] = {};

PyObject* NewError(py::module_& m, const char* name, const char* doc, PyObject* base) {
  const std::string qualified = std::string("grove.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return type;
}

void MakeErrors(py::module_& m) {
  g_grove_error = NewError(m, "GroveError",
                           "Every error grove raises. `code` holds the status code's name "
                           "(\"invalid argument\", \"data loss\", ...), `message` the message.",
                           PyExc_Exception);
  struct Spec {
    StatusCode code;
    const char* name;
    PyObject* builtin;  // a built-in exception the class also derives from, or null
    const char* doc;
  };
  const Spec specs[] = {
      {StatusCode::kInvalidArgument, "InvalidArgumentError", PyExc_ValueError,
       "A configuration value or an input record breaks a rule (also a ValueError). The filter "
       "is unchanged by the call that raised it."},
      {StatusCode::kNotFound, "NotFoundError", PyExc_LookupError,
       "Something that must exist "
       "does not."},
      {StatusCode::kOutOfRange, "OutOfRangeError", nullptr,
       "A particle left the map grid; the filter must not be stepped again."},
      {StatusCode::kFailedPrecondition, "FailedPreconditionError", PyExc_RuntimeError,
       "The call is not valid in the filter's state (for example every weight became zero, or "
       "a checkpoint made under another configuration)."},
      {StatusCode::kResourceExhausted, "ResourceExhaustedError", PyExc_MemoryError,
       "No memory for a result."},
      {StatusCode::kDataLoss, "DataLossError", nullptr, "A corrupt or truncated checkpoint."},
      {StatusCode::kIoError, "IoError", PyExc_OSError, "The operating system refused an I/O."},
      {StatusCode::kInternal, "InternalError", PyExc_RuntimeError,
       "A broken internal invariant (a bug in grove)."},
  };
  for (const Spec& s : specs) {
    py::tuple bases = s.builtin != nullptr
                          ? py::make_tuple(py::handle(g_grove_error), py::handle(s.builtin))
                          : py::make_tuple(py::handle(g_grove_error));
    g_errors[static_cast<int>(s.code)] = NewError(m, s.name, s.doc, bases.ptr());
  }
}

// Raises the exception of `status`'s code; the message is `context` followed by the status's.
[[noreturn]] void Raise(const Status& status, const std::string& context = "") {
  PyObject* type = g_errors[static_cast<int>(status.code())];
  if (type == nullptr) type = g_grove_error;
  const std::string message = context + status.message();
  py::object error = py::reinterpret_borrow<py::object>(type)(message);
  error.attr("code") = StatusCodeName(status.code());
  error.attr("message") = message;
  PyErr_SetObject(type, error.ptr());
  throw py::error_already_set();
}

[[noreturn]] void RaiseInvalid(const std::string& message) { Raise(InvalidArgumentError(message)); }

void ThrowIfError(const Status& status, const std::string& context = "") {
  if (!status.ok()) Raise(status, context);
}

template <typename T>
T ValueOrRaise(StatusOr<T> result, const std::string& context = "") {
  if (!result.ok()) Raise(result.status(), context);
  return std::move(result).value();
}

// ---- Configurations ----

// Python's name of a value's type, for messages.
std::string TypeName(py::handle value) { return Py_TYPE(value.ptr())->tp_name; }

// `value` as the field's value, or InvalidArgument naming the key. Integers are Python ints or
// anything with __index__ (numpy integers), never bool; reals also take ints and anything with
// __float__ that is not text; choices are strings.
StatusOr<FieldValue> FieldValueFromPython(const FieldInfo& info, py::handle value) {
  PyObject* o = value.ptr();
  const bool is_bool = PyBool_Check(o);
  const bool is_text = PyUnicode_Check(o) || PyBytes_Check(o);
  auto wrong = [&](const char* expected) {
    // A string quoted as the JSON configuration's messages quote it, anything else by its repr.
    std::string text = PyUnicode_Check(o) ? QuoteForMessage(py::cast<std::string>(value))
                                          : py::cast<std::string>(py::repr(value));
    if (text.size() > 64) text = text.substr(0, 64) + "...";
    return InvalidArgumentError(std::string(info.name) + " = " + text + ": must be " + expected +
                                ", found " + TypeName(value));
  };
  FieldValue result;
  switch (info.type) {
    case FieldType::kInteger:
    case FieldType::kUnsigned: {
      if (is_bool || !PyIndex_Check(o)) {
        return wrong(info.type == FieldType::kInteger ? "an integer" : "a non-negative integer");
      }
      py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(o));
      if (!i) throw py::error_already_set();
      int overflow = 0;
      const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
      if (info.type == FieldType::kInteger) {
        if (overflow != 0) return wrong("an integer in range");
        result = static_cast<int64_t>(v);
      } else {
        if (overflow < 0 || (overflow == 0 && v < 0)) return wrong("a non-negative integer");
        const unsigned long long u = PyLong_AsUnsignedLongLong(i.ptr());
        if (u == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
          PyErr_Clear();
          return wrong("a non-negative integer below 2**64");
        }
        result = static_cast<uint64_t>(u);
      }
      break;
    }
    case FieldType::kReal: {
      const bool numeric = PyIndex_Check(o) || (Py_TYPE(o)->tp_as_number != nullptr &&
                                                Py_TYPE(o)->tp_as_number->nb_float != nullptr);
      if (is_bool || is_text || !numeric) return wrong("a number");
      const double v = PyFloat_AsDouble(o);
      if (v == -1.0 && PyErr_Occurred()) {
        PyErr_Clear();
        return wrong("a number");
      }
      result = v;
      break;
    }
    case FieldType::kChoice: {
      int64_t index = -1;
      if (PyUnicode_Check(o)) {
        const std::string name = value.cast<std::string>();
        for (size_t k = 0; k < info.choices.size(); ++k) {
          if (info.choices[k] == name) index = static_cast<int64_t>(k);
        }
      }
      if (index < 0) {
        std::string choices;
        for (const std::string& c : info.choices) {
          choices += (choices.empty() ? "\"" : ", \"") + c + "\"";
        }
        return wrong(("one of " + choices).c_str());
      }
      result = index;
      break;
    }
  }
  GROVE_RETURN_IF_ERROR(CheckFieldValue(info, result));
  return result;
}

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

py::object FieldValueToPython(const FieldInfo& info, const FieldValue& value) {
  if (info.type == FieldType::kChoice) return py::str(FormatFieldValue(info, value));
  return std::visit([](auto v) -> py::object { return py::cast(v); }, value);
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

// ---- Values and arrays ----

py::handle g_pose_type;  // grove.Pose, a namedtuple (x, y, heading)

py::object PoseTuple(const Pose2& p) { return g_pose_type(p.x_m, p.y_m, p.heading_rad); }

static_assert(sizeof(StampedPose) == 4 * sizeof(double) && offsetof(StampedPose, t_s) == 0 &&
              offsetof(StampedPose, pose) == sizeof(double) && offsetof(Pose2, x_m) == 0 &&
              offsetof(Pose2, y_m) == sizeof(double) &&
              offsetof(Pose2, heading_rad) == 2 * sizeof(double));

// (n, 4) float64 [t, x, y, heading], a copy.
py::array_t<double> TrajectoryArray(const std::vector<StampedPose>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}});
  if (!poses.empty())
    std::memcpy(out.mutable_data(), poses.data(), poses.size() * sizeof(poses[0]));
  return out;
}

// A structured dtype whose layout is T's: the caller checks the offsets with static_asserts.
py::dtype StructDtype(const std::vector<std::pair<const char*, py::object>>& fields,
                      const std::vector<size_t>& offsets, size_t itemsize) {
  py::list names, formats, offs;
  for (size_t k = 0; k < fields.size(); ++k) {
    names.append(fields[k].first);
    formats.append(fields[k].second);
    offs.append(offsets[k]);
  }
  py::dict spec;
  spec["names"] = names;
  spec["formats"] = formats;
  spec["offsets"] = offs;
  spec["itemsize"] = itemsize;
  return py::reinterpret_steal<py::dtype>(
      py::module_::import("numpy").attr("dtype")(spec).release());
}

static_assert(std::is_standard_layout_v<HexCounts> && offsetof(HexCounts, q) == 0 &&
              offsetof(HexCounts, r) == 4 && offsetof(HexCounts, x_m) == 8 &&
              offsetof(HexCounts, y_m) == 16 && offsetof(HexCounts, counts) == 24 &&
              sizeof(HexCounts) == 72);
static_assert(std::is_standard_layout_v<LandmarkEstimate> && offsetof(LandmarkEstimate, id) == 0 &&
              offsetof(LandmarkEstimate, x_m) == 8 && offsetof(LandmarkEstimate, y_m) == 16 &&
              offsetof(LandmarkEstimate, sxx) == 24 && offsetof(LandmarkEstimate, sxy) == 32 &&
              offsetof(LandmarkEstimate, syy) == 40 &&
              offsetof(LandmarkEstimate, source_id) == 48 && sizeof(LandmarkEstimate) == 56);

py::handle g_hex_dtype;       // q, r (int32), x, y (f8), counts (f8, (6,))
py::handle g_landmark_dtype;  // id (int64), x, y, sxx, sxy, syy (f8), source_id (int64)

void MakeDtypes(py::module_& m) {
  py::object f8 = py::str("<f8"), i4 = py::str("<i4"), i8 = py::str("<i8");
  g_hex_dtype =
      StructDtype({{"q", i4}, {"r", i4}, {"x", f8}, {"y", f8}, {"counts", py::make_tuple(f8, 6)}},
                  {offsetof(HexCounts, q), offsetof(HexCounts, r), offsetof(HexCounts, x_m),
                   offsetof(HexCounts, y_m), offsetof(HexCounts, counts)},
                  sizeof(HexCounts))
          .release();
  g_landmark_dtype = StructDtype({{"id", i8},
                                  {"x", f8},
                                  {"y", f8},
                                  {"sxx", f8},
                                  {"sxy", f8},
                                  {"syy", f8},
                                  {"source_id", i8}},
                                 {offsetof(LandmarkEstimate, id), offsetof(LandmarkEstimate, x_m),
                                  offsetof(LandmarkEstimate, y_m), offsetof(LandmarkEstimate, sxx),
                                  offsetof(LandmarkEstimate, sxy), offsetof(LandmarkEstimate, syy),
                                  offsetof(LandmarkEstimate, source_id)},
                                 sizeof(LandmarkEstimate))
                         .release();
  m.attr("HEX_DTYPE") = g_hex_dtype;
  m.attr("LANDMARK_DTYPE") = g_landmark_dtype;
}

// A structured array of `dtype` holding a copy of `items` (T's layout is the dtype's).
template <typename T>
py::array StructArray(py::handle dtype, const std::vector<T>& items) {
  py::array out(py::reinterpret_borrow<py::dtype>(dtype),
                std::vector<py::ssize_t>{static_cast<py::ssize_t>(items.size())});
  if (!items.empty()) std::memcpy(out.mutable_data(), items.data(), items.size() * sizeof(T));
  return out;
}

// `map` as a contiguous array of grove.HEX_DTYPE: a one-dimensional structured array with at
// least the fields q, r and counts (x and y, when there, are copied too), fields taken by name.
py::array HexArray(const py::object& map) {
  py::object np = py::module_::import("numpy");
  py::array given = np.attr("asarray")(map);
  const py::object names = given.dtype().attr("names");
  const char* missing = nullptr;
  for (const char* field : {"q", "r", "counts"}) {
    if (names.is_none() || !names.contains(field)) {
      missing = field;
      break;
    }
  }
  if (missing != nullptr) {
    throw py::type_error(
        "map: expected a structured array of grove.HEX_DTYPE (as cumulative_map() "
        "returns), found " +
        py::cast<std::string>(py::str(given.dtype())) + " values without field " + missing);
  }
  if (given.ndim() != 1) {
    throw py::value_error(
        "map: must be one-dimensional, a structured array of grove.HEX_DTYPE (as "
        "cumulative_map() returns)");
  }
  py::array out = np.attr("zeros")(given.shape(0), py::reinterpret_borrow<py::dtype>(g_hex_dtype));
  for (const char* field : {"q", "r", "x", "y", "counts"}) {
    if (names.contains(field)) out[field] = given[field];
  }
  return out;
}

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// `value` as a C-contiguous float64 array (a copy only when it is not one already). Only real
// numbers are taken (integers and floats, not booleans, complex numbers, text or objects): a
// TypeError names the dtype found. Running out of memory converting is a MemoryError.
DoubleArray AsDoubles(const py::object& value, const char* what) {
  py::array any = py::array::ensure(value);
  if (!any) {
    throw py::type_error(std::string(what) + ": expected an array of numbers, not " +
                         TypeName(value));
  }
  const char kind = any.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'f') {
    throw py::type_error(std::string(what) +
                         ": expected real numbers (integers or floats), found " +
                         py::cast<std::string>(py::str(any.dtype())) + " values");
  }
  // numpy's own conversion, whose MemoryError reaches the caller (ensure() would clear it).
  py::object doubles =
      py::module_::import("numpy").attr("ascontiguousarray")(any, py::dtype::of<double>());
  return DoubleArray::ensure(doubles);
}

// The rows of an (n, cols) array, copied (the filter reads them with the GIL released).
std::vector<double> Rows(const py::object& value, const char* what, py::ssize_t min_cols,
                         py::ssize_t max_cols, py::ssize_t* cols) {
  DoubleArray a = AsDoubles(value, what);
  if (a.ndim() == 1 && a.shape(0) == 0) {
    *cols = min_cols;
    return {};
  }
  if (a.ndim() != 2 || a.shape(1) < min_cols || a.shape(1) > max_cols) {
    std::string shape = "(";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) {
      shape += (k ? ", " : "") + std::to_string(a.shape(k)) + (a.ndim() == 1 ? "," : "");
    }
    RaiseInvalid(std::string(what) + ": expected shape (n, " + std::to_string(min_cols) +
                 (max_cols > min_cols ? " or " + std::to_string(max_cols) : "") + "), found " +
                 shape + ")");
  }
  *cols = a.shape(1);
  return std::vector<double>(a.data(), a.data() + a.size());
}

std::vector<double> Column(const py::object& value, const char* what) {
  DoubleArray a = AsDoubles(value, what);
  if (a.ndim() != 1) {
    RaiseInvalid(std::string(what) + ": expected a 1-D array, found " + std::to_string(a.ndim()) +
                 " dimensions");
  }
  return std::vector<double>(a.data(), a.data() + a.size());
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// Detections as observations: (n, 2) [range, bearing] get id -1, (n, 3) carry their id, which
// must be a whole number. `first` is the row of `rows` that starts them, for messages.
Status ToObservations(const double* rows, size_t n, py::ssize_t cols, size_t first,
                      const char* what, std::vector<LandmarkObservation>* out) {
  out->clear();
  for (size_t k = 0; k < n; ++k) {
    const double* row = rows + k * cols;
    LandmarkObservation z{row[0], row[1], -1};
    if (cols == 3) {
      const double id = row[2];
      if (!(std::floor(id) == id && std::fabs(id) < 9.2e18)) {
        return InvalidArgumentError(std::string(what) + " row " + std::to_string(first + k) +
                                    ": id = " + Number(id) + ": must be a whole number");
      }
      z.id = static_cast<int64_t>(id);
    }
    out->push_back(z);
  }
  return Status::Ok();
}

py::dict MemoryDict(const MemoryUse& m) {
  py::dict d;
  d["live_nodes"] = m.live_nodes;
  d["live_bytes"] = m.live_bytes;
  d["peak_live_nodes"] = m.peak_live_nodes;
  d["peak_live_bytes"] = m.peak_live_bytes;
  d["reserved_bytes"] = m.reserved_bytes;
  return d;
}

py::dict FilterSummaryDict(const FilterSummary& s) {
  py::dict d;
  d["particles"] = s.particles;
  d["threads_requested"] = s.threads_requested;
  d["threads_used"] = s.threads_used;
  d["steps"] = s.steps;
  d["resamplings"] = s.resamplings;
  d["mean_ess"] = s.mean_ess;
  d["advance_s"] = s.advance_s;
  d["normalize_s"] = s.normalize_s;
  d["resample_s"] = s.resample_s;
  d["release_s"] = s.release_s;
  d["bookkeeping_s"] = s.bookkeeping_s;
  d["filter_s"] = s.filter_s();
  d["loops"] = s.loops;
  d["loop_s"] = s.loop_s;
  d["loop_busy_s"] = s.loop_busy_s;
  return d;
}

// Lets Ctrl-C stop a long run(): at most every 0.1 s the GIL is taken to run Python's signal
// handlers. Returns false (the Python error set) when one raised. REQUIRES: the GIL is released.
class SignalPoller {
 public:
  bool Ok() {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return true;
    last_ = now;
    py::gil_scoped_acquire gil;
    return PyErr_CheckSignals() == 0;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// ---- The filters ----

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

using PyFootSlam = Filter<FootSlam, FootSlamConfig>;
using PyFastSlam = Filter<FastSlam, FastSlamConfig>;

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

// The methods both filters share, bound on `cls`.
template <typename Engine, typename Config, typename Class>
void BindCommon(Class& cls, const char* name, const std::vector<ConfigField<Config>>* fields) {
  using F = Filter<Engine, Config>;
  cls.def_property_readonly(
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
          "heaviest_trajectory",
          [](const F& f) {
            return TrajectoryArray(
                ValueOrRaise(f.Locked([](Engine& e) { return e.HeaviestTrajectory(); })));
          },
          "The heaviest particle's path traced through its ancestry, at the times of "
          "mean_trajectory(): a new float64 array of shape (n, 4), columns t, x, y, heading.")
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
      .def(
          "check_invariants",
          [](const F& f) { ThrowIfError(f.Locked([](Engine& e) { return e.CheckInvariants(); })); },
          "Walks the whole shared state and checks every reference count; raises InternalError "
          "naming a broken rule. Slow; for tests.")
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
}

const char* const kThreadRules =
    "\n\nThread safety: one filter is used by one thread at a time; the module enforces this "
    "with a mutex per object, so calls on one object from several threads serialise (a call "
    "waits for the one in progress). Two filters share nothing and run in parallel in two Python "
    "threads, because every call releases the GIL while it filters. Every returned array is a "
    "new copy owned by the caller: it stays valid after later steps and after the filter is "
    "gone.";

// ---- FootSlam ----

void RunSteps(const PyFootSlam& f, const std::vector<double>& t, const std::vector<double>& dx,
              const std::vector<double>& dy) {
  const size_t n = t.size();
  size_t failed_row = n;
  bool interrupted = false;
  Status status = f.Locked([&](FootSlam& e) {
    SignalPoller poller;
    for (size_t k = 0; k < n; ++k) {
      Status s = e.Step(t[k], dx[k], dy[k]);
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
  if (!status.ok()) {
    Raise(status, "row " + std::to_string(failed_row) + " (t = " + Number(t[failed_row]) + "): ");
  }
}

py::dict FootSlamSummaryDict(const FootSlamSummary& s) {
  py::dict d = FilterSummaryDict(s);
  d["mean_scale"] = s.mean_scale;
  d["mean_heading_error_rad"] = s.mean_heading_error_rad;
  d["grid_size"] = s.grid_size;
  d["prior_hexagons"] = s.prior_hexagons;
  d["prior_hexagons_outside"] = s.prior_hexagons_outside;
  d["stored_blocks"] = s.stored_blocks;
  d["stored_blocks_exact"] = s.stored_blocks_exact;
  d["stored_hexagons"] = s.stored_hexagons;
  d["store_s"] = s.store_s;
  d["map_memory"] = MemoryDict(s.map_memory);
  d["trajectory_memory"] = MemoryDict(s.trajectory_memory);
  d["report"] = s.BriefReport();
  return d;
}

void BindFootSlam(py::module_& m) {
  const auto* fields = &FootSlamConfigFields();
  const std::string doc =
      std::string(
          "FootSLAM: pedestrian SLAM from step odometry on a hexagon grid (a Rao-Blackwellized "
          "particle filter whose particles share their maps).\n\n"
          "FootSlam(config=None, **kwargs): `config` is a dict of configuration keys (the "
          "grove command's JSON keys; FootSlam.config_fields() lists them), keyword arguments "
          "override it. An unknown key or a bad value raises InvalidArgumentError naming it; "
          "nothing is built then.") +
      kThreadRules;
  py::class_<PyFootSlam> cls(m, "FootSlam", doc.c_str());
  cls.def(py::init([fields](const py::object& config, const py::kwargs& kwargs) {
            return CreateFilter<FootSlam>(MakeConfig(*fields, config, kwargs));
          }),
          py::arg("config") = py::none())
      .def(
          "step",
          [](const PyFootSlam& f, double t, double dx, double dy) {
            ThrowIfError(f.Locked([&](FootSlam& e) { return e.Step(t, dx, dy); }));
          },
          py::arg("t"), py::arg("dx"), py::arg("dy"),
          "Processes one odometry step: time t (s, after the previous step's), displacement "
          "dx, dy in the odometry frame (m). Raises InvalidArgumentError (filter unchanged) for a "
          "non-finite value or a time not after the previous one; OutOfRangeError when a "
          "particle leaves a fixed grid or a step crosses more than 8 x grid_size hexagons, and "
          "FailedPreconditionError when the filter degenerated "
          "(the filter must not be stepped again after these two).")
      .def(
          "run",
          [](const PyFootSlam& f, const py::object& steps, const py::object& dx,
             const py::object& dy) {
            std::vector<double> t, x, y;
            if (dx.is_none() && dy.is_none()) {
              py::ssize_t cols = 0;
              std::vector<double> rows = Rows(steps, "steps", 3, 3, &cols);
              const size_t n = rows.size() / 3;
              t.resize(n);
              x.resize(n);
              y.resize(n);
              for (size_t k = 0; k < n; ++k) {
                t[k] = rows[3 * k];
                x[k] = rows[3 * k + 1];
                y[k] = rows[3 * k + 2];
              }
            } else {
              if (dx.is_none() || dy.is_none()) {
                throw py::type_error("run(): give steps as one (n, 3) array or as t, dx, dy");
              }
              t = Column(steps, "t");
              x = Column(dx, "dx");
              y = Column(dy, "dy");
              if (x.size() != t.size() || y.size() != t.size()) {
                RaiseInvalid("run(): t, dx and dy have lengths " + std::to_string(t.size()) + ", " +
                             std::to_string(x.size()) + " and " + std::to_string(y.size()));
              }
            }
            RunSteps(f, t, x, y);
          },
          py::arg("steps"), py::arg("dx") = py::none(), py::arg("dy") = py::none(),
          "Processes many steps in one call with the GIL released: `steps` is an array of shape "
          "(n, 3), columns t, dx, dy (anything numpy converts to float64), or run(t, dx, dy) with "
          "three 1-D arrays. Stops at the first failing step and raises its error, prefixed "
          "with \"row k (t = ...): \"; the rows before it stay applied. Ctrl-C stops it between "
          "steps (KeyboardInterrupt, the steps so far applied).")
      .def(
          "set_start_time",
          [](const PyFootSlam& f, double t) {
            ThrowIfError(f.Locked([&](FootSlam& e) { return e.SetStartTime(t); }));
          },
          py::arg("t"),
          "Sets the time of the start pose (the first step must come after it); without it the "
          "start takes the first step's time. FailedPreconditionError after the first step.")
      .def(
          "set_prior_map",
          [](const PyFootSlam& f, const py::object& map) {
            py::array a = HexArray(map);
            std::vector<HexCounts> hexes(static_cast<size_t>(a.shape(0)));
            if (!hexes.empty())
              std::memcpy(hexes.data(), a.data(), hexes.size() * sizeof(HexCounts));
            ThrowIfError(f.Locked([&](FootSlam& e) { return e.SetPriorMap(hexes); }));
          },
          py::arg("map"),
          "Sets a prior map: the cumulative_map() of an earlier walk through the same area, in "
          "this "
          "filter's map frame (a structured array of grove.HEX_DTYPE; q, r and counts are read). "
          "Each crossing's counts gain prior_map_confidence times the prior's. Before the first "
          "step (FailedPreconditionError after it); InvalidArgumentError naming the row for a "
          "negative or non-finite count or a hexagon given twice.")
      .def(
          "smoothed_trajectory",
          [](const PyFootSlam& f) {
            return TrajectoryArray(
                ValueOrRaise(f.Locked([](FootSlam& e) { return e.SmoothedTrajectory(); })));
          },
          "The smoothed path, for offline mapping: at the times of mean_trajectory(), the "
          "weighted mean under the final weights of the surviving particles' ancestral poses. "
          "A new float64 array of shape (n, 4), columns t, x, y, heading.")
      .def(
          "cumulative_map",
          [](const PyFootSlam& f) {
            return StructArray(
                g_hex_dtype, ValueOrRaise(f.Locked([](FootSlam& e) { return e.CumulativeMap(); })));
          },
          "The weight-averaged map over all particles (eq. 5-6 of the paper): a new structured "
          "array of grove.HEX_DTYPE, one element per visited hexagon in key order, fields q, r "
          "(int32 axial coordinates), x, y (float64 centre, m) and counts (float64, 6 edge "
          "counters).")
      .def(
          "heaviest_map",
          [](const PyFootSlam& f) {
            return StructArray(g_hex_dtype,
                               ValueOrRaise(f.Locked([](FootSlam& e) { return e.HeaviestMap(); })));
          },
          "The heaviest particle's own map, as cumulative_map() (whole-number counts), plus the "
          "stored map.")
      .def(
          "stored_map",
          [](const PyFootSlam& f) {
            return StructArray(g_hex_dtype,
                               ValueOrRaise(f.Locked([](FootSlam& e) { return e.StoredMap(); })));
          },
          "Storage of diversity (store_distance_m): the weighted mean counters of the map "
          "areas folded so far, as cumulative_map(); empty when nothing was stored.")
      .def(
          "summary",
          [](const PyFootSlam& f) {
            return FootSlamSummaryDict(f.Locked([](FootSlam& e) { return e.Summary(); }));
          },
          "What the run asked for, used and cost, as a dict; 'report' is the one-paragraph "
          "summary the grove command prints.")
      .def_static(
          "resume",
          [fields](py::bytes data, const py::object& config, const py::kwargs& kwargs) {
            return ResumeFilter<FootSlam>(MakeConfig(*fields, config, kwargs), data);
          },
          py::arg("data"), py::arg("config") = py::none(),
          "A filter continuing from checkpoint bytes made by checkpoint() under a configuration "
          "equal in every field but threads and batch (give it as to the constructor). Stepping "
          "it gives, bit for bit, what the checkpointed filter would have given. Raises "
          "DataLossError for corrupt bytes and FailedPreconditionError for a different "
          "configuration (naming the field).")
      .def_static(
          "estimate_peak_bytes",
          [fields](int64_t steps, const py::object& config, const py::kwargs& kwargs) {
            return FootSlam::EstimatePeakBytes(MakeConfig(*fields, config, kwargs), steps);
          },
          py::arg("steps"), py::arg("config") = py::none(),
          "A prediction of the peak memory in bytes of a run of `steps` steps under the "
          "configuration (7 to 22 % above the peak RSS of the measured runs).");
  BindCommon<FootSlam, FootSlamConfig>(cls, "FootSlam", fields);
}

// ---- FastSlam ----

py::dict FastSlamSummaryDict(const FastSlamSummary& s) {
  py::dict d = FilterSummaryDict(s);
  d["controls"] = s.controls;
  d["scans"] = s.scans;
  d["observations"] = s.observations;
  d["predict_steps"] = s.predict_steps;
  d["landmarks"] = s.landmarks;
  py::dict a;
  a["associated"] = s.association.associated;
  a["created"] = s.association.created;
  a["ignored"] = s.association.ignored;
  a["removed"] = s.association.removed;
  a["dropped"] = s.association.dropped;
  a["tagged"] = s.association.tagged;
  a["wrong"] = s.association.wrong;
  d["association"] = a;
  py::dict ev;
  ev["trials"] = s.evolution.trials;
  ev["accepted"] = s.evolution.accepted;
  d["evolution"] = ev;
  d["map_memory"] = MemoryDict(s.map_memory);
  d["trajectory_memory"] = MemoryDict(s.trajectory_memory);
  d["report"] = s.BriefReport();
  return d;
}

// Feeds controls (m, 3) [t, speed, steer] and detections (k, 3|4) [t, range, bearing(, id)] in
// the order of the grove command: each control, then every scan (the detections of one time)
// from its time up to the next control's.
void RunFastSlam(const PyFastSlam& f, const std::vector<double>& controls,
                 const std::vector<double>& detections, py::ssize_t dcols) {
  const size_t m = controls.size() / 3;
  const size_t k_total = detections.size() / dcols;
  auto dt = [&](size_t k) { return detections[k * dcols]; };
  for (size_t k = 1; k < k_total; ++k) {
    if (!(dt(k) >= dt(k - 1))) {
      RaiseInvalid("detections row " + std::to_string(k) + " (t = " + Number(dt(k)) +
                   "): times must not decrease");
    }
  }
  if (k_total > 0 && (m == 0 || dt(0) < controls[0])) {
    RaiseInvalid("detections row 0 (t = " + Number(dt(0)) + "): before the first control");
  }
  std::string context;
  bool interrupted = false;
  Status status = f.Locked([&](FastSlam& e) {
    SignalPoller poller;
    std::vector<double> obs;
    std::vector<LandmarkObservation> scan;
    size_t z = 0;
    for (size_t c = 0; c < m; ++c) {
      const double* row = &controls[3 * c];
      Status s = e.Control(row[0], row[1], row[2]);
      if (!s.ok()) {
        context = "controls row " + std::to_string(c) + " (t = " + Number(row[0]) + "): ";
        return s;
      }
      const double upper = c + 1 < m ? controls[3 * (c + 1)] : INFINITY;
      while (z < k_total && dt(z) < upper) {
        const double t = dt(z);
        const size_t first = z;
        obs.clear();
        for (; z < k_total && dt(z) == t; ++z) {
          obs.insert(obs.end(), &detections[z * dcols + 1], &detections[z * dcols + dcols]);
        }
        s = ToObservations(obs.data(), z - first, dcols - 1, first, "detections", &scan);
        if (s.ok()) s = e.Scan(t, scan);
        if (!s.ok()) {
          context = "scan at t = " + Number(t) + " (detections rows " + std::to_string(first) +
                    ".." + std::to_string(z - 1) + "): ";
          return s;
        }
      }
      if (!poller.Ok()) {
        interrupted = true;
        break;
      }
    }
    return Status::Ok();
  });
  if (interrupted) throw py::error_already_set();
  ThrowIfError(status, context);
}

void BindFastSlam(py::module_& m) {
  const auto* fields = &FastSlamConfigFields();
  const std::string doc =
      std::string(
          "Landmark FastSLAM 1.0 / 2.0 (and the seed's sigma-point family): a vehicle among "
          "point landmarks seen by a range-bearing sensor.\n\n"
          "FastSlam(config=None, **kwargs): configuration keys as FootSlam's "
          "(FastSlam.config_fields() lists them). Time: the first control() sets the start "
          "time; a control holds until the next one; scan() predicts to its time and updates.") +
      kThreadRules;
  py::class_<PyFastSlam> cls(m, "FastSlam", doc.c_str());
  cls.def(py::init([fields](const py::object& config, const py::kwargs& kwargs) {
            return CreateFilter<FastSlam>(MakeConfig(*fields, config, kwargs));
          }),
          py::arg("config") = py::none())
      .def(
          "control",
          [](const PyFastSlam& f, double t, double speed, double steer) {
            ThrowIfError(f.Locked([&](FastSlam& e) { return e.Control(t, speed, steer); }));
          },
          py::arg("t"), py::arg("speed"), py::arg("steer"),
          "A control (speed m/s, steering angle rad) from time t on: predicts to t with the "
          "control held so far, then holds this one. InvalidArgumentError (filter unchanged) for "
          "a non-finite value or a bad time.")
      .def(
          "scan",
          [](const PyFastSlam& f, double t, const py::object& observations) {
            py::ssize_t cols = 0;
            std::vector<double> rows = Rows(observations, "observations", 2, 3, &cols);
            std::vector<LandmarkObservation> scan;
            ThrowIfError(
                ToObservations(rows.data(), rows.size() / cols, cols, 0, "observations", &scan));
            ThrowIfError(f.Locked([&](FastSlam& e) { return e.Scan(t, scan); }));
          },
          py::arg("t"), py::arg("observations"),
          "A scan at time t: `observations` is an array of shape (n, 2), columns range (m) and "
          "bearing (rad, in (-pi, pi]), or (n, 3) with the landmark id as third column (known "
          "association needs it; without it the id is -1). Predicts to t, then updates every "
          "particle. InvalidArgumentError (filter unchanged) for a bad time or observation (the "
          "message names its index); FailedPreconditionError when the filter degenerated.")
      .def(
          "run",
          [](const PyFastSlam& f, const py::object& controls, const py::object& detections) {
            py::ssize_t ccols = 0, dcols = 0;
            std::vector<double> c = Rows(controls, "controls", 3, 3, &ccols);
            std::vector<double> d = detections.is_none()
                                        ? std::vector<double>()
                                        : Rows(detections, "detections", 3, 4, &dcols);
            if (d.empty()) dcols = 3;
            RunFastSlam(f, c, d, dcols);
          },
          py::arg("controls"), py::arg("detections") = py::none(),
          "Feeds a whole run in one call with the GIL released: `controls` of shape (m, 3), "
          "columns t, speed, steer; `detections` of shape (k, 3) or (k, 4), columns t, range, "
          "bearing (and id), sorted by time, the rows of one time making one scan. Each control "
          "is followed by the scans from its time up to the next control's (as the grove "
          "command feeds them). Raises the first error, naming the row; what came before stays "
          "applied.")
      .def(
          "pose_covariance",
          [](const PyFastSlam& f) {
            const Pose2Covariance c = f.Locked([](FastSlam& e) { return e.PoseCovariance(); });
            py::array_t<double> out({3, 3});
            double* p = out.mutable_data();
            const double v[9] = {c.xx, c.xy, c.xh, c.xy, c.yy, c.yh, c.xh, c.yh, c.hh};
            std::memcpy(p, v, sizeof(v));
            return out;
          },
          "The weighted covariance of the particles' poses about their mean after the last "
          "step: a new 3x3 float64 array over (x, y, heading).")
      .def(
          "landmarks",
          [](const PyFastSlam& f) {
            return StructArray(
                g_landmark_dtype,
                ValueOrRaise(f.Locked([](FastSlam& e) { return e.HeaviestLandmarks(); })));
          },
          "The heaviest particle's landmarks in id order: a new structured array of "
          "grove.LANDMARK_DTYPE, fields id (int64), x, y (m), sxx, sxy, syy (covariance, m^2) "
          "and source_id (int64; under unknown association the id of the creating observation, "
          "-1 for none).")
      .def(
          "summary",
          [](const PyFastSlam& f) {
            return FastSlamSummaryDict(f.Locked([](FastSlam& e) { return e.Summary(); }));
          },
          "What the run asked for, used and cost, as a dict; 'report' is the one-paragraph "
          "summary.")
      .def_static(
          "resume",
          [fields](py::bytes data, const py::object& config, const py::kwargs& kwargs) {
            return ResumeFilter<FastSlam>(MakeConfig(*fields, config, kwargs), data);
          },
          py::arg("data"), py::arg("config") = py::none(),
          "A filter continuing from checkpoint bytes, as FootSlam.resume().");
  BindCommon<FastSlam, FastSlamConfig>(cls, "FastSlam", fields);
}

py::dict VersionDict() {
  const VersionInfo v = Version();
  py::dict d;
  d["version"] = v.version;
  d["major"] = v.major;
  d["minor"] = v.minor;
  d["patch"] = v.patch;
  d["commit"] = v.commit;
  d["compiler"] = v.compiler;
  d["build_type"] = v.build_type;
  d["simd_targets"] = v.simd_targets;
  d["simd_target"] = v.simd_target;
  d["string"] = VersionString();
  return d;
}

// The module's first step on import. An interpreter other than the one the module was built for
// usually fails here (no numpy on its path), so the error names both interpreters and the ways
// out instead of pybind11's bare "initialization failed" (GROVE_PYTHON_BUILT_FOR: CMakeLists.txt).
void RequireNumpy() {
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set& e) {
    py::module_ sys = py::module_::import("sys");
    const std::string here = py::str(sys.attr("executable")).cast<std::string>() + ", Python " +
                             py::str(sys.attr("version")).cast<std::string>();
    throw py::import_error(
        "grove: numpy cannot be imported (" + std::string(e.what()) + ") by this interpreter (" +
        here +
        "); grove was built for " GROVE_PYTHON_BUILT_FOR
        ": run that interpreter, install numpy for this one, or build grove for this one "
        "(pip install --no-build-isolation ./engine/bindings/python from the source tree)");
  }
}

}  // namespace

// grove.FootImu (foot_imu_binding.cc); `raise` raises a status as the module's exception.
void BindFootImu(py::module_& m, void (*raise)(const Status& status, const std::string& context));

}  // namespace grove::python

PYBIND11_MODULE(grove, m) {
  namespace py = pybind11;
  using namespace grove::python;
  m.doc() =
      "grove: particle-filter SLAM (FootSLAM on hexagon grids, landmark FastSLAM) whose particles "
      "share persistent maps.\n\n"
      "Classes: FootSlam, FastSlam, FootImu (foot IMU samples to steps); errors: GroveError and "
      "one subclass per status code "
      "(InvalidArgumentError is also a ValueError). Every failing call raises with the engine's "
      "message and leaves the filter as it was unless the error says otherwise.\n\n"
      "Threads: one filter is used by one thread at a time (a mutex per object serialises the "
      "calls on it); two filters share nothing and run in parallel in two Python threads, since "
      "every call releases the GIL while it filters. Arrays returned are copies owned by the "
      "caller: they stay valid after later steps and after the filter is gone.";
  RequireNumpy();
  MakeErrors(m);
  g_pose_type = py::module_::import("collections")
                    .attr("namedtuple")("Pose", py::make_tuple("x", "y", "heading"))
                    .release();
  g_pose_type.attr("__module__") = "grove";
  g_pose_type.attr("__doc__") = "A pose in the map frame: x, y (m), heading (rad).";
  m.attr("Pose") = g_pose_type;
  MakeDtypes(m);
  m.attr("__version__") = grove::Version().version;
  m.def("version", &VersionDict,
        "This build: a dict with version, major, minor, patch, commit, compiler, build_type, "
        "simd_targets (compiled in, best first), simd_target (the one this machine runs) and "
        "string (the one-line form).");
  BindFootSlam(m);
  BindFastSlam(m);
  BindFootImu(
      m, [](const grove::Status& status, const std::string& context) { Raise(status, context); });
  // A Python function, so that pickle finds it by name at every protocol (a bound C++ function
  // is pickled through its capsule, which protocols 0 and 1 cannot do).
  m.def(
      "_initialised",
      [](py::handle self) {
        if (py::detail::get_type_info(Py_TYPE(self.ptr())) == nullptr) {
          throw py::type_error("expected a grove object, found " + TypeName(self));
        }
        auto* instance = reinterpret_cast<py::detail::instance*>(self.ptr());
        return instance->get_value_and_holder().holder_constructed();
      },
      "Whether a grove object's C++ part exists (for the guards of __init__ and __setstate__).");
  py::exec(R"(
def _refuse_when_initialised(cls, name):
    """pybind11 ignores __init__ and __setstate__ on a live object; refuse them instead."""
    original = getattr(cls, name)
    def guarded(self, *args, **kwargs):
        if _initialised(self):
            raise TypeError("%s.%s(): the object is already initialised; make a new one"
                            % (type(self).__name__, name))
        return original(self, *args, **kwargs)
    guarded.__name__ = name
    guarded.__qualname__ = cls.__name__ + "." + name
    guarded.__doc__ = original.__doc__
    setattr(cls, name, guarded)

_refuse_when_initialised(FootImu, "__init__")
for _cls in (FootSlam, FastSlam):
    _refuse_when_initialised(_cls, "__init__")
    _refuse_when_initialised(_cls, "__setstate__")
del _cls

def _restore(name, config, data):
    """Rebuilds a pickled filter from its class name, configuration and checkpoint bytes."""
    if name not in ("FootSlam", "FastSlam"):
        raise InvalidArgumentError("_restore: name = %r: must be FootSlam or FastSlam" % (name,))
    return globals()[name].resume(data, config)
)",
           m.attr("__dict__"));
}
