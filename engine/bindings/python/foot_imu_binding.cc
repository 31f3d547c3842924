// grove.FootImu over grove/foot_imu.h. The configuration goes through the JSON reader of the
// configuration tables (a dict is dumped by Python's json module), so its messages name the key,
// the value and the rule exactly as the grove command's --imu-config does.
//
// Thread safety: as the filters of grove_module.cc, a mutex per object, taken with the GIL
// released. grove_module.cc declares BindFootImu() and lends it its error raising (the bindings
// include public headers only, so the two files share no header).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "grove/config_json.h"
#include "grove/foot_imu.h"
#include "grove/status.h"

namespace grove::python {
namespace {

namespace py = pybind11;

// Raises the module's exception of `status`'s code, the message prefixed with `context`.
using RaiseStatusFn = void (*)(const Status& status, const std::string& context);
RaiseStatusFn g_raise = nullptr;

void ThrowIfError(const Status& status, const std::string& context = "") {
  if (!status.ok()) g_raise(status, context);
}

// The columns of take_steps()'s array.
const char* const kStepColumns[] = {"t",
                                    "dx",
                                    "dy",
                                    "dz",
                                    "dheading",
                                    "var_dx",
                                    "cov_dx_dy",
                                    "var_dy",
                                    "cov_dx_dheading",
                                    "cov_dy_dheading",
                                    "var_dheading",
                                    "stance_begin",
                                    "stance_end"};
constexpr py::ssize_t kStepColumnCount = sizeof(kStepColumns) / sizeof(kStepColumns[0]);

FootImuConfig MakeConfig(const py::object& config, const py::kwargs& kwargs) {
  py::dict merged;
  if (!config.is_none()) {
    if (!py::isinstance(config, py::module_::import("collections.abc").attr("Mapping"))) {
      throw py::type_error("config must be a dict of configuration keys, not " +
                           std::string(Py_TYPE(config.ptr())->tp_name));
    }
    for (auto [key, value] : py::dict(config)) merged[key] = value;
  }
  for (auto [key, value] : kwargs) merged[key] = value;
  for (auto [key, value] : merged) {
    if (PyFloat_Check(value.ptr()) && !std::isfinite(PyFloat_AsDouble(value.ptr()))) {
      ThrowIfError(InvalidArgumentError(py::str(key).cast<std::string>() + " = " +
                                        py::repr(value).cast<std::string>() + ": must be finite"));
    }
  }
  py::object dumps = py::module_::import("json").attr("dumps");
  std::string text;
  try {
    text = py::cast<std::string>(dumps(merged));
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError)) throw;
    ThrowIfError(
        InvalidArgumentError(std::string("config: ") + py::str(e.value()).cast<std::string>()));
  }
  FootImuConfig result;
  ThrowIfError(ApplyConfigJson(FootImuConfigFields(), "config", text, &result));
  ThrowIfError(result.Validate());
  return result;
}

py::dict ConfigDict(const FootImuConfig& config) {
  return py::module_::import("json").attr("loads")(ConfigToJson(FootImuConfigFields(), config));
}

class PyFootImu {
 public:
  explicit PyFootImu(const FootImuConfig& config) {
    StatusOr<std::unique_ptr<FootImu>> made = [&] {
      py::gil_scoped_release release;
      return FootImu::Create(config);
    }();
    ThrowIfError(made.status());
    imu_ = std::move(*made);
  }

  template <typename F>
  auto Locked(F&& f) const {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mu_);
    return f(*imu_);
  }

 private:
  std::unique_ptr<FootImu> imu_;
  mutable std::mutex mu_;
};

// (n, 7) rows [t, ax, ay, az, gx, gy, gz] as samples.
std::vector<ImuSample> Samples(const py::object& value) {
  using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
  DoubleArray a = DoubleArray::ensure(value);
  if (!a) throw py::error_already_set();
  if (a.ndim() == 1 && a.shape(0) == 0) return {};
  if (a.ndim() != 2 || a.shape(1) != 7) {
    ThrowIfError(InvalidArgumentError(
        "samples: expected shape (n, 7), columns t, ax, ay, az, gx, gy, gz (s, m/s^2, rad/s)"));
  }
  std::vector<ImuSample> out(static_cast<size_t>(a.shape(0)));
  const double* d = a.data();
  for (size_t k = 0; k < out.size(); ++k, d += 7) {
    out[k].t_s = d[0];
    for (int i = 0; i < 3; ++i) {
      out[k].accel_mps2[i] = d[1 + i];
      out[k].gyro_radps[i] = d[4 + i];
    }
  }
  return out;
}

py::array_t<double> StepArray(const std::vector<FootStep>& steps) {
  py::array_t<double> out({static_cast<py::ssize_t>(steps.size()), kStepColumnCount});
  double* d = out.mutable_data();
  for (const FootStep& s : steps) {
    const Pose2Covariance& c = s.covariance;
    for (double v : {s.t_s, s.dx_m, s.dy_m, s.dz_m, s.dheading_rad, c.xx, c.xy, c.yy, c.xh, c.yh,
                     c.hh, s.stance_begin_s, s.stance_end_s}) {
      *d++ = v;
    }
  }
  return out;
}

// Adds every sample; raises naming the row of the first refused one (the engine then holds
// the rows before it).
void AddSamples(const PyFootImu& f, const std::vector<ImuSample>& samples) {
  size_t failed = samples.size();
  Status status = f.Locked([&](FootImu& e) {
    for (size_t k = 0; k < samples.size(); ++k) {
      if (Status s = e.AddSample(samples[k]); !s.ok()) {
        failed = k;
        return s;
      }
    }
    return Status::Ok();
  });
  ThrowIfError(status, "row " + std::to_string(failed) + ": ");
}

py::dict SummaryDict(const FootImuSummary& s) {
  py::dict d;
  d["samples"] = s.samples;
  d["processed_samples"] = s.processed_samples;
  d["still_samples"] = s.still_samples;
  d["stances"] = s.stances;
  d["steps"] = s.steps;
  d["aligned"] = s.aligned;
  d["alignment_t"] = s.alignment_t_s;
  d["origin_t"] = s.has_origin ? py::cast(s.origin_t_s) : py::none();
  d["gravity"] = s.gravity_mps2;
  d["distance"] = s.distance_m;
  d["seconds"] = s.seconds;
  d["report"] = s.BriefReport();
  return d;
}

py::dict StateDict(const FootImuState& s) {
  auto vec = [](const double* v) { return py::make_tuple(v[0], v[1], v[2]); };
  py::dict d;
  d["t"] = s.t_s;
  d["position"] = vec(s.position_m);
  d["velocity"] = vec(s.velocity_mps);
  d["roll"] = s.roll_rad;
  d["pitch"] = s.pitch_rad;
  d["heading"] = s.heading_rad;
  d["accel_bias"] = vec(s.accel_bias_mps2);
  d["gyro_bias"] = vec(s.gyro_bias_radps);
  d["still"] = s.still;
  return d;
}

}  // namespace

void BindFootImu(py::module_& m, RaiseStatusFn raise) {
  g_raise = raise;
  py::tuple columns(kStepColumnCount);
  for (py::ssize_t k = 0; k < kStepColumnCount; ++k) columns[k] = kStepColumns[k];
  const std::string doc =
      "The foot IMU front end: a foot-mounted IMU's samples to the steps FootSlam walks on (a "
      "zero-velocity-aided inertial navigation system; engine/imu/README.md gives its frames, "
      "units and equations).\n\n"
      "FootImu(config=None, **kwargs): `config` is a dict of the front end's keys (the grove "
      "command's --imu-config keys; FootImu.default_config() lists them), keyword arguments "
      "override it; an unknown key or a bad value raises InvalidArgumentError naming it.\n\n"
      "Samples are rows t, ax, ay, az, gx, gy, gz: seconds, specific force in m/s^2 (+g upwards "
      "at rest) and angular rate in rad/s, sensor frame. Steps come back as a float64 array of "
      "shape (n, 13) whose columns FootImu.STEP_COLUMNS names; steps[:, :3] is what "
      "FootSlam.run() takes.\n\n"
      "Thread safety: a mutex per object; calls release the GIL.";
  py::class_<PyFootImu> cls(m, "FootImu", doc.c_str());
  cls.attr("STEP_COLUMNS") = columns;
  cls.def(py::init([](const py::object& config, const py::kwargs& kwargs) {
            return std::make_unique<PyFootImu>(MakeConfig(config, kwargs));
          }),
          py::arg("config") = py::none())
      .def_static(
          "default_config", [] { return ConfigDict(FootImuConfig()); },
          "Every configuration key with its default, as a dict.")
      .def(
          "add_samples",
          [](const PyFootImu& f, const py::object& samples) { AddSamples(f, Samples(samples)); },
          py::arg("samples"),
          "Adds the rows of an (n, 7) array [t, ax, ay, az, gx, gy, gz] in order. Raises "
          "InvalidArgumentError naming the row for a value that is not finite, a saturated axis, "
          "a time not after the previous or more than max_sample_interval_s after it; the rows "
          "before it are taken. FailedPreconditionError after finish().")
      .def(
          "finish",
          [](const PyFootImu& f) { ThrowIfError(f.Locked([](FootImu& e) { return e.Finish(); })); },
          "The end of the recording: decides the samples the detector held back and ends a "
          "stance still open as a step.")
      .def(
          "take_steps",
          [](const PyFootImu& f) {
            return StepArray(f.Locked([](FootImu& e) { return e.TakeSteps(); }));
          },
          "The steps finished since the last call, oldest first: a new float64 array of shape "
          "(n, 13), columns STEP_COLUMNS (s, m, rad; the covariance of dx, dy, dheading).")
      .def(
          "state",
          [](const PyFootImu& f) {
            return StateDict(f.Locked([](FootImu& e) { return e.State(); }));
          },
          "The navigation state after the last sample the filter processed: a dict (t, "
          "position, velocity, roll, pitch, heading, accel_bias, gyro_bias, still).")
      .def(
          "summary",
          [](const PyFootImu& f) {
            return SummaryDict(f.Locked([](FootImu& e) { return e.Summary(); }));
          },
          "What the run read and found: a dict (samples, still_samples, stances, steps, "
          "distance, origin_t, gravity, seconds, report, ...).")
      .def_property_readonly(
          "config",
          [](const PyFootImu& f) {
            return ConfigDict(f.Locked([](FootImu& e) { return e.config(); }));
          },
          "The configuration in use, every key.");
  m.def(
      "foot_imu_steps",
      [](const py::object& samples, const py::object& config, const py::kwargs& kwargs) {
        PyFootImu f(MakeConfig(config, kwargs));
        AddSamples(f, Samples(samples));
        ThrowIfError(f.Locked([](FootImu& e) { return e.Finish(); }));
        return StepArray(f.Locked([](FootImu& e) { return e.TakeSteps(); }));
      },
      py::arg("samples"), py::arg("config") = py::none(),
      "The steps of a whole recording in one call: FootImu(config, **kwargs), add_samples(), "
      "finish(), take_steps().");
}

}  // namespace grove::python
