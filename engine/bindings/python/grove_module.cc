// The `grove` Python module: every model's class (one file each: footslam_module.cc,
// fastslam_module.cc, tracker_module.cc) and the foot IMU front end (foot_imu_binding.cc) on the
// shared layer (filter_binding.h, python_values.h), over the public headers alone.
#include <pybind11/eval.h>
#include <pybind11/pybind11.h>

#include "engine/bindings/python/model_bindings.h"
#include "engine/bindings/python/python_values.h"
#include "grove/version.h"

namespace grove::python {
namespace {

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

}  // namespace grove::python

PYBIND11_MODULE(grove, m) {
  namespace py = pybind11;
  using namespace grove::python;
  m.doc() =
      "grove: particle filters (FootSLAM on hexagon grids, landmark FastSLAM, range-only beacon "
      "tracking) whose particles share persistent maps.\n\n"
      "Classes: FootSlam, FastSlam, Tracker, FootImu (foot IMU samples to steps); errors: "
      "GroveError and one subclass per status code "
      "(InvalidArgumentError is also a ValueError). Every failing call raises with the engine's "
      "message and leaves the filter as it was unless the error says otherwise.\n\n"
      "Threads: one filter is used by one thread at a time (a mutex per object serialises the "
      "calls on it); two filters share nothing and run in parallel in two Python threads, since "
      "every call releases the GIL while it filters. Arrays returned are copies owned by the "
      "caller: they stay valid after later steps and after the filter is gone.";
  RequireNumpy();
  MakeErrors(m);
  MakePoseType(m);
  m.attr("__version__") = grove::Version().version;
  m.def("version", &VersionDict,
        "This build: a dict with version, major, minor, patch, commit, compiler, build_type, "
        "simd_targets (compiled in, best first), simd_target (the one this machine runs) and "
        "string (the one-line form).");
  py::tuple filters = py::make_tuple(BindFootSlam(m), BindFastSlam(m), BindTracker(m));
  m.attr("_filters") = filters;
  BindFootImu(m);
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
for _name in _filters:
    _refuse_when_initialised(globals()[_name], "__init__")
    _refuse_when_initialised(globals()[_name], "__setstate__")
del _name

def _restore(name, config, data):
    """Rebuilds a pickled filter from its class name, configuration and checkpoint bytes."""
    if name not in _filters:
        raise InvalidArgumentError("_restore: name = %r: must be one of %s"
                                   % (name, ", ".join(_filters)))
    return globals()[name].resume(data, config)
)",
           m.attr("__dict__"));
}
