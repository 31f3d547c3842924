// grove.FastSlam (engine/bindings/python): landmark FastSLAM's inputs (controls, scans, whole
// runs) and read-outs (landmarks, pose covariance) on the class every model shares
// (filter_binding.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "engine/bindings/python/filter_binding.h"
#include "engine/bindings/python/model_bindings.h"
#include "engine/bindings/python/python_values.h"
#include "grove/fastslam.h"

namespace grove::python {
namespace {

using PyFastSlam = Filter<FastSlam, FastSlamConfig>;

static_assert(std::is_standard_layout_v<LandmarkEstimate> && offsetof(LandmarkEstimate, id) == 0 &&
              offsetof(LandmarkEstimate, x_m) == 8 && offsetof(LandmarkEstimate, y_m) == 16 &&
              offsetof(LandmarkEstimate, sxx) == 24 && offsetof(LandmarkEstimate, sxy) == 32 &&
              offsetof(LandmarkEstimate, syy) == 40 &&
              offsetof(LandmarkEstimate, source_id) == 48 && sizeof(LandmarkEstimate) == 56);

py::handle g_landmark_dtype;  // id (int64), x, y, sxx, sxy, syy (f8), source_id (int64)

void MakeLandmarkDtype(py::module_& m) {
  py::object f8 = py::str("<f8"), i8 = py::str("<i8");
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
  m.attr("LANDMARK_DTYPE") = g_landmark_dtype;
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
  a["truncated"] = s.association.truncated;
  d["association"] = a;
  py::dict ev;
  ev["trials"] = s.evolution.trials;
  ev["accepted"] = s.evolution.accepted;
  d["evolution"] = ev;
  d["map_memory"] = MemoryDict(s.map_memory);
  d["trajectory_memory"] = MemoryDict(s.trajectory_memory);
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
  std::vector<double> obs;
  std::vector<LandmarkObservation> scan;
  size_t z = 0;
  // One row per control: the control, then its scans.
  auto control_and_scans = [&](FastSlam& e, size_t c) -> Status {
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
        context = "scan at t = " + Number(t) + " (detections rows " + std::to_string(first) + ".." +
                  std::to_string(z - 1) + "): ";
        return s;
      }
    }
    return Status::Ok();
  };
  RunRows(f, m, control_and_scans, [&](size_t) { return context; });
}

}  // namespace

const char* BindFastSlam(py::module_& m) {
  MakeLandmarkDtype(m);
  auto cls = BindFilter<FastSlam>(
      m, "FastSlam",
      "Landmark FastSLAM 1.0 / 2.0 (and the seed's sigma-point family): a vehicle among "
      "point landmarks seen by a range-bearing sensor.\n\n"
      "FastSlam(config=None, **kwargs): configuration keys as FootSlam's "
      "(FastSlam.config_fields() lists them). Time: the first control() sets the start "
      "time; a control holds until the next one; scan() predicts to its time and updates.",
      &FastSlamConfigFields(), FastSlamSummaryDict);
  cls.def(
         "control",
         [](const PyFastSlam& f, double t, double speed, double steer) {
           ThrowIfError(f.Locked([&](FastSlam& e) { return e.Control(t, speed, steer); }));
         },
         py::arg("t"), py::arg("speed"), py::arg("steer"),
         "A control (speed m/s, steering angle rad) from time t on: predicts to t with the "
         "control held so far, then holds this one. InvalidArgumentError (filter unchanged) for "
         "a non-finite value or a bad time. The prediction runs with the next scan or read-out "
         "(the predictions since the last scan in one pass); an error inside it is raised by "
         "that scan or read-out, or by the next call that can raise.")
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
          "-1 for none).");
  return "FastSlam";
}

}  // namespace grove::python
