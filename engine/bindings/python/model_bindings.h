// The models' Python classes: each adds its class (and the types only it uses) to the module and
// returns the class's name (grove._restore rebuilds a pickled filter by that name).
#ifndef GROVE_ENGINE_BINDINGS_PYTHON_MODEL_BINDINGS_H_
#define GROVE_ENGINE_BINDINGS_PYTHON_MODEL_BINDINGS_H_

#include <pybind11/pybind11.h>

namespace grove::python {

const char* BindFootSlam(pybind11::module_& m);  // footslam_module.cc
const char* BindFastSlam(pybind11::module_& m);  // fastslam_module.cc
const char* BindTracker(pybind11::module_& m);   // tracker_module.cc

// grove.FootImu (foot_imu_binding.cc): foot IMU samples to steps, a front end and no filter.
void BindFootImu(pybind11::module_& m);

}  // namespace grove::python

#endif  // GROVE_ENGINE_BINDINGS_PYTHON_MODEL_BINDINGS_H_
