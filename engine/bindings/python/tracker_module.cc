// grove.Tracker (engine/bindings/python): the beacon tracker's inputs (updates, whole runs) and
// read-out (the mean state) on the class every model shares (filter_binding.h).
#include <pybind11/pybind11.h>

#include <cstddef>
#include <string>
#include <vector>

#include "engine/bindings/python/filter_binding.h"
#include "engine/bindings/python/model_bindings.h"
#include "engine/bindings/python/python_values.h"
#include "grove/tracking.h"

namespace grove::python {
namespace {

using PyTracker = Filter<Tracker, TrackerConfig>;

// Rows [beacon_x, beacon_y, range] (`stride` doubles apart, from `rows`) as measurements.
std::vector<RangeMeasurement> Ranges(const double* rows, size_t count, size_t stride) {
  std::vector<RangeMeasurement> z(count);
  for (size_t k = 0; k < count; ++k)
    z[k] = {rows[k * stride], rows[k * stride + 1], rows[k * stride + 2]};
  return z;
}

// A whole run: rows [t, beacon_x, beacon_y, range] sorted by t, the rows of one time an update.
void RunTracker(const PyTracker& f, const py::object& measurements) {
  py::ssize_t cols = 0;
  const std::vector<double> rows = Rows(measurements, "measurements", 4, 4, &cols);
  const size_t n = rows.size() / 4;
  std::vector<size_t> starts;  // the first row of each update, then n
  for (size_t k = 0; k < n; ++k) {
    if (k > 0 && !(rows[4 * k] >= rows[4 * (k - 1)])) {
      RaiseInvalid("measurements row " + std::to_string(k) + " (t = " + Number(rows[4 * k]) +
                   "): times must not decrease");
    }
    if (k == 0 || rows[4 * k] != rows[4 * (k - 1)]) starts.push_back(k);
  }
  starts.push_back(n);
  RunRows(
      f, starts.size() - 1,
      [&](Tracker& e, size_t u) {
        return e.Update(rows[4 * starts[u]],
                        Ranges(&rows[4 * starts[u] + 1], starts[u + 1] - starts[u], 4));
      },
      [&](size_t u) {
        return "update at t = " + Number(rows[4 * starts[u]]) + " (measurements rows " +
               std::to_string(starts[u]) + ".." + std::to_string(starts[u + 1] - 1) + "): ";
      });
}

// One update: `ranges` of shape (n, 3), columns beacon x, beacon y, range.
void Update(const PyTracker& f, double t, const py::object& ranges) {
  py::ssize_t cols = 0;
  const std::vector<double> rows = Rows(ranges, "ranges", 3, 3, &cols);
  const std::vector<RangeMeasurement> z = Ranges(rows.data(), rows.size() / 3, 3);
  ThrowIfError(f.Locked([&](Tracker& e) { return e.Update(t, z); }));
}

py::dict TrackerSummaryDict(const TrackerSummary& s) {
  py::dict d = FilterSummaryDict(s);
  d["measurements"] = s.measurements;
  return d;
}

}  // namespace

const char* BindTracker(py::module_& m) {
  auto cls = BindFilter<Tracker>(
      m, "Tracker",
      "Range-only beacon tracking: a target moving at nearly constant velocity, tracked by a "
      "bootstrap particle filter from its ranges to beacons at known positions.\n\n"
      "Tracker(config=None, **kwargs): configuration keys as FootSlam's "
      "(Tracker.config_fields() lists them). Poses' heading is the direction of motion.",
      &TrackerConfigFields(), TrackerSummaryDict);
  cls.def(
         "mean_state",
         [](const PyTracker& f) {
           const TargetState s = f.Locked([](Tracker& e) { return e.MeanState(); });
           return py::make_tuple(s.x_m, s.y_m, s.vx_mps, s.vy_mps);
         },
         "The weighted mean state after the last update: a tuple (x, y, vx, vy), metres and "
         "m/s.")
      .def("update", &Update, py::arg("t"), py::arg("ranges"),
           "Moves every particle to time t (s, after the previous update's), then weights it by "
           "`ranges`, an array of shape (n, 3): columns beacon x, beacon y (m) and the measured "
           "range (m, >= 0); n = 0 predicts. InvalidArgumentError (tracker unchanged) for a bad "
           "time or range (the message names its index); FailedPreconditionError when the filter "
           "degenerated.")
      .def("run", &RunTracker, py::arg("measurements"),
           "Feeds a whole run in one call with the GIL released: `measurements` of shape (k, 4), "
           "columns t, beacon x, beacon y, range, sorted by time, the rows of one time making "
           "one update. Raises the first error, naming the rows; what came before stays applied. "
           "Ctrl-C stops it between updates (KeyboardInterrupt).");
  return "Tracker";
}

}  // namespace grove::python
