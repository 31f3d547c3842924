// The Python module's shared values (python_values.h).
#include "engine/bindings/python/python_values.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace grove::python {
namespace {

py::handle g_pose_type;  // grove.Pose

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

}  // namespace

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

void Raise(const Status& status, const std::string& context) {
  PyObject* type = g_errors[static_cast<int>(status.code())];
  if (type == nullptr) type = g_grove_error;
  const std::string message = context + status.message();
  py::object error = py::reinterpret_borrow<py::object>(type)(message);
  error.attr("code") = StatusCodeName(status.code());
  error.attr("message") = message;
  PyErr_SetObject(type, error.ptr());
  throw py::error_already_set();
}

void RaiseInvalid(const std::string& message) { Raise(InvalidArgumentError(message)); }

void ThrowIfError(const Status& status, const std::string& context) {
  if (!status.ok()) Raise(status, context);
}

std::string TypeName(py::handle value) { return Py_TYPE(value.ptr())->tp_name; }

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

py::object FieldValueToPython(const FieldInfo& info, const FieldValue& value) {
  if (info.type == FieldType::kChoice) return py::str(FormatFieldValue(info, value));
  return std::visit([](auto v) -> py::object { return py::cast(v); }, value);
}

void MakePoseType(py::module_& m) {
  g_pose_type = py::module_::import("collections")
                    .attr("namedtuple")("Pose", py::make_tuple("x", "y", "heading"))
                    .release();
  g_pose_type.attr("__module__") = "grove";
  g_pose_type.attr("__doc__") = "A pose in the map frame: x, y (m), heading (rad).";
  m.attr("Pose") = g_pose_type;
}

py::object PoseTuple(const Pose2& p) { return g_pose_type(p.x_m, p.y_m, p.heading_rad); }

static_assert(sizeof(StampedPose) == 4 * sizeof(double) && offsetof(StampedPose, t_s) == 0 &&
              offsetof(StampedPose, pose) == sizeof(double) && offsetof(Pose2, x_m) == 0 &&
              offsetof(Pose2, y_m) == sizeof(double) &&
              offsetof(Pose2, heading_rad) == 2 * sizeof(double));

py::array_t<double> TrajectoryArray(const std::vector<StampedPose>& poses) {
  py::array_t<double> out({static_cast<py::ssize_t>(poses.size()), py::ssize_t{4}});
  if (!poses.empty())
    std::memcpy(out.mutable_data(), poses.data(), poses.size() * sizeof(poses[0]));
  return out;
}

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

const char* const kThreadRules =
    "\n\nThread safety: one filter is used by one thread at a time; the module enforces this "
    "with a mutex per object, so calls on one object from several threads serialise (a call "
    "waits for the one in progress). Two filters share nothing and run in parallel in two Python "
    "threads, because every call releases the GIL while it filters. Every returned array is a "
    "new copy owned by the caller: it stays valid after later steps and after the filter is "
    "gone.";
}  // namespace grove::python
