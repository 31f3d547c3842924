// What every model's Python class shares below the filter wrapper (filter_binding.h): grove's
// exception classes, configuration values from and to Python objects, poses and arrays, the
// summary's filter part as a dict, and the poller that lets Ctrl-C stop a long call.
#ifndef GROVE_ENGINE_BINDINGS_PYTHON_PYTHON_VALUES_H_
#define GROVE_ENGINE_BINDINGS_PYTHON_PYTHON_VALUES_H_

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove::python {

namespace py = pybind11;

// The exception classes, one per status code, all subclasses of grove.GroveError, added to `m`.
void MakeErrors(py::module_& m);
// Raises the exception of `status`'s code; the message is `context` followed by the status's.
[[noreturn]] void Raise(const Status& status, const std::string& context = "");
[[noreturn]] void RaiseInvalid(const std::string& message);
void ThrowIfError(const Status& status, const std::string& context = "");

template <typename T>
T ValueOrRaise(StatusOr<T> result, const std::string& context = "") {
  if (!result.ok()) Raise(result.status(), context);
  return std::move(result).value();
}

// Python's name of a value's type, for messages.
std::string TypeName(py::handle value);
// `value` as the field's value, or InvalidArgument naming the key. Integers are Python ints or
// anything with __index__ (numpy integers), never bool; reals also take ints and anything with
// __float__ that is not text; choices are strings.
StatusOr<FieldValue> FieldValueFromPython(const FieldInfo& info, py::handle value);
py::object FieldValueToPython(const FieldInfo& info, const FieldValue& value);

// grove.Pose, a namedtuple (x, y, heading), added to `m`.
void MakePoseType(py::module_& m);
py::object PoseTuple(const Pose2& p);

// (n, 4) float64 [t, x, y, heading], a copy.
py::array_t<double> TrajectoryArray(const std::vector<StampedPose>& poses);

// A structured dtype whose layout is T's: the caller checks the offsets with static_asserts.
py::dtype StructDtype(const std::vector<std::pair<const char*, py::object>>& fields,
                      const std::vector<size_t>& offsets, size_t itemsize);

// A structured array of `dtype` holding a copy of `items` (T's layout is the dtype's).
template <typename T>
py::array StructArray(py::handle dtype, const std::vector<T>& items) {
  py::array out(py::reinterpret_borrow<py::dtype>(dtype),
                std::vector<py::ssize_t>{static_cast<py::ssize_t>(items.size())});
  if (!items.empty()) std::memcpy(out.mutable_data(), items.data(), items.size() * sizeof(T));
  return out;
}

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// `value` as a C-contiguous float64 array (a copy only when it is not one already). Only real
// numbers are taken (integers and floats, not booleans, complex numbers, text or objects): a
// TypeError names the dtype found. Running out of memory converting is a MemoryError.
DoubleArray AsDoubles(const py::object& value, const char* what);
// The rows of an (n, cols) array with min_cols <= cols <= max_cols, copied (the filter reads them
// with the GIL released); *cols receives cols. InvalidArgumentError naming the shape otherwise.
std::vector<double> Rows(const py::object& value, const char* what, py::ssize_t min_cols,
                         py::ssize_t max_cols, py::ssize_t* cols);
// A 1-D array, copied.
std::vector<double> Column(const py::object& value, const char* what);
// `v` with 17 significant digits, for messages.
std::string Number(double v);

py::dict MemoryDict(const MemoryUse& m);
// The summary's filter part: particles, threads, steps, resamplings, ESS, phase times, loops.
py::dict FilterSummaryDict(const FilterSummary& s);

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

// The class docstrings' paragraph on threads and ownership.
extern const char* const kThreadRules;

}  // namespace grove::python

#endif  // GROVE_ENGINE_BINDINGS_PYTHON_PYTHON_VALUES_H_
