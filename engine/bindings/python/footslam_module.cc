// grove.FootSlam (engine/bindings/python): FootSLAM's inputs (steps, the start time, a prior
// map) and read-outs (smoothed trajectory, maps) on the class every model shares
// (filter_binding.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "engine/bindings/python/filter_binding.h"
#include "engine/bindings/python/model_bindings.h"
#include "engine/bindings/python/python_values.h"
#include "grove/footslam.h"

namespace grove::python {
namespace {

using PyFootSlam = Filter<FootSlam, FootSlamConfig>;

static_assert(std::is_standard_layout_v<HexCounts> && offsetof(HexCounts, q) == 0 &&
              offsetof(HexCounts, r) == 4 && offsetof(HexCounts, x_m) == 8 &&
              offsetof(HexCounts, y_m) == 16 && offsetof(HexCounts, counts) == 24 &&
              sizeof(HexCounts) == 72);

py::handle g_hex_dtype;  // q, r (int32), x, y (f8), counts (f8, (6,))

void MakeHexDtype(py::module_& m) {
  py::object f8 = py::str("<f8"), i4 = py::str("<i4");
  g_hex_dtype =
      StructDtype({{"q", i4}, {"r", i4}, {"x", f8}, {"y", f8}, {"counts", py::make_tuple(f8, 6)}},
                  {offsetof(HexCounts, q), offsetof(HexCounts, r), offsetof(HexCounts, x_m),
                   offsetof(HexCounts, y_m), offsetof(HexCounts, counts)},
                  sizeof(HexCounts))
          .release();
  m.attr("HEX_DTYPE") = g_hex_dtype;
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

void RunSteps(const PyFootSlam& f, const std::vector<double>& t, const std::vector<double>& dx,
              const std::vector<double>& dy) {
  RunRows(
      f, t.size(), [&](FootSlam& e, size_t k) { return e.Step(t[k], dx[k], dy[k]); },
      [&](size_t k) { return "row " + std::to_string(k) + " (t = " + Number(t[k]) + "): "; });
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
  return d;
}

}  // namespace

const char* BindFootSlam(py::module_& m) {
  MakeHexDtype(m);
  const auto* fields = &FootSlamConfigFields();
  auto cls = BindFilter<FootSlam>(
      m, "FootSlam",
      "FootSLAM: pedestrian SLAM from step odometry on a hexagon grid (a Rao-Blackwellized "
      "particle filter whose particles share their maps).\n\n"
      "FootSlam(config=None, **kwargs): `config` is a dict of configuration keys (the "
      "grove command's JSON keys; FootSlam.config_fields() lists them), keyword arguments "
      "override it. An unknown key or a bad value raises InvalidArgumentError naming it; "
      "nothing is built then.",
      fields, FootSlamSummaryDict);
  cls.def(
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
      .def_static(
          "estimate_peak_bytes",
          [fields](int64_t steps, const py::object& config, const py::kwargs& kwargs) {
            return FootSlam::EstimatePeakBytes(MakeConfig(*fields, config, kwargs), steps);
          },
          py::arg("steps"), py::arg("config") = py::none(),
          "A prediction of the peak memory in bytes of a run of `steps` steps under the "
          "configuration (7 to 22 % above the peak RSS of the measured runs).");
  return "FootSlam";
}

}  // namespace grove::python
