"""Tests of the grove Python module (engine/bindings/python/grove_module.cc): the embedder's view.

Run from a build: ctest -R python_test, or by hand with the module's directory on PYTHONPATH:
  PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_grove
GROVE_WALK_STEPS names the bundled walk (tools/data/building_walk_steps.csv); without it the
path relative to this file is used.
"""

import math
import os
import pickle
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import numpy as np

import grove

HERE = os.path.dirname(os.path.abspath(__file__))
WALK_STEPS = os.environ.get(
    "GROVE_WALK_STEPS",
    os.path.join(HERE, "..", "..", "tools", "data", "building_walk_steps.csv"))

# Small and quick: every FootSlam of these tests has few particles on one or two threads.
SMALL = {"particles": 200, "seed": 7, "threads": 1}


def square_walk(loops=3, side_steps=10, step_m=0.7, seed=3):
    """A square loop walked `loops` times: (n, 3) float64 [t, dx, dy], a 1 % scale error and a
    little heading noise."""
    rng = np.random.default_rng(seed)
    headings = np.repeat(np.arange(4) * (math.pi / 2), side_steps)
    headings = np.tile(headings, loops) + rng.normal(0, 0.03, 4 * side_steps * loops)
    n = headings.size
    steps = np.empty((n, 3))
    steps[:, 0] = 0.5 * (np.arange(n) + 1)
    steps[:, 1] = 1.01 * step_m * np.cos(headings)
    steps[:, 2] = 1.01 * step_m * np.sin(headings)
    return steps


def load_walk():
    return np.loadtxt(WALK_STEPS, delimiter=",", skiprows=1, ndmin=2)


class ModuleTest(unittest.TestCase):
    def test_version(self):
        v = grove.version()
        self.assertEqual(grove.__version__, v["version"])
        self.assertEqual(v["version"], "%d.%d.%d" % (v["major"], v["minor"], v["patch"]))
        for key in ("commit", "compiler", "simd_targets", "simd_target", "string"):
            self.assertIsInstance(v[key], str)
        self.assertIn(v["version"], v["string"])

    def test_error_hierarchy(self):
        self.assertTrue(issubclass(grove.GroveError, Exception))
        self.assertTrue(issubclass(grove.InvalidArgumentError, grove.GroveError))
        self.assertTrue(issubclass(grove.InvalidArgumentError, ValueError))
        self.assertTrue(issubclass(grove.FailedPreconditionError, grove.GroveError))
        self.assertTrue(issubclass(grove.DataLossError, grove.GroveError))

    def test_docstrings_state_the_thread_rules(self):
        for doc in (grove.__doc__, grove.FootSlam.__doc__, grove.FastSlam.__doc__):
            self.assertIn("GIL", doc)
            self.assertIn("one thread at a time", doc)
            self.assertRegex(doc, "cop(y|ies) owned by the caller")
        for cls in (grove.FootSlam, grove.FastSlam):
            for name in dir(cls):
                if name.startswith("_"):
                    continue
                member = getattr(cls, name)
                doc = member.__doc__ or ""
                if callable(member):  # pybind11 puts the signature first, then the docstring
                    doc = doc.partition("\n\n")[2]
                self.assertGreater(len(doc.strip()), 10, cls.__name__ + "." + name)


class FootSlamConfigTest(unittest.TestCase):
    def test_dict_and_kwargs_with_kwargs_winning(self):
        f = grove.FootSlam({"particles": 100, "seed": 3, "weighting": "prior_ratio"}, seed=5,
                           threads=1)
        c = f.config
        self.assertEqual(c["particles"], 100)
        self.assertEqual(c["seed"], 5)
        self.assertEqual(c["weighting"], "prior_ratio")
        self.assertEqual(c["threads"], 1)
        self.assertEqual(c["hex_radius_m"], 0.5)  # a default

    def test_config_has_every_key_and_round_trips(self):
        f = grove.FootSlam(SMALL, hex_radius_m=0.75)
        names = [field["name"] for field in grove.FootSlam.config_fields()]
        self.assertEqual(list(f.config), names)
        self.assertEqual(grove.FootSlam(f.config).config, f.config)

    def test_numpy_scalars_are_accepted(self):
        f = grove.FootSlam(particles=np.int64(50), hex_radius_m=np.float32(0.5), threads=1)
        self.assertEqual(f.config["particles"], 50)

    def test_unknown_key_names_it_and_the_nearest(self):
        with self.assertRaises(grove.InvalidArgumentError) as cm:
            grove.FootSlam(partcles=10)
        self.assertIn('unknown key "partcles"', str(cm.exception))
        self.assertIn('did you mean "particles"', str(cm.exception))
        self.assertEqual(cm.exception.code, "invalid argument")
        self.assertIsInstance(cm.exception, ValueError)
        with self.assertRaisesRegex(grove.InvalidArgumentError, 'unknown key "bogus"'):
            grove.FootSlam({"bogus": 1})

    def test_bad_values_name_the_key_value_and_rule(self):
        cases = [
            ({"particles": 0}, r"particles = 0: must be"),
            ({"particles": "many"}, r'particles = "many": must be an integer, found str'),
            ({"particles": True}, r"particles = .*must be an integer, found bool"),
            ({"seed": -1}, r"seed = -1: must be a non-negative integer"),
            ({"hex_radius_m": float("nan")}, r"hex_radius_m = nan"),
            ({"hex_radius_m": "0.5"}, r"hex_radius_m = .*must be a number, found str"),
            ({"weighting": "bogus"}, r'weighting = .*one of "paper", "prior_ratio"'),
            ({"grid_size": 100}, r"grid_size"),  # Validate(): not a power of sqrt(degree)
        ]
        for config, pattern in cases:
            with self.subTest(config=config):
                with self.assertRaisesRegex(grove.InvalidArgumentError, pattern):
                    grove.FootSlam(config)
        with self.assertRaises(TypeError):
            grove.FootSlam(42)

    def test_repr_shows_the_configuration_and_rebuilds_it(self):
        f = grove.FootSlam(particles=100, seed=7, threads=1, weighting="prior_ratio")
        text = repr(f)
        self.assertEqual(
            text, "grove.FootSlam(particles=100, seed=7, weighting='prior_ratio', threads=1)")
        self.assertEqual(eval(text, {"grove": grove}).config, f.config)
        self.assertEqual(repr(grove.FootSlam(particles=30, hex_radius_m=0.25)),
                         "grove.FootSlam(particles=30, seed=1, hex_radius_m=0.25)")


class FootSlamRunTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.walk = square_walk()

    def run_walk(self, steps=None, **config):
        f = grove.FootSlam(SMALL, **config)
        f.run(self.walk if steps is None else steps)
        return f

    def assertSameFilter(self, a, b):
        np.testing.assert_array_equal(a.mean_trajectory(), b.mean_trajectory())
        np.testing.assert_array_equal(a.heaviest_trajectory(), b.heaviest_trajectory())
        self.assertEqual(a.cumulative_map().tobytes(), b.cumulative_map().tobytes())
        self.assertEqual(a.heaviest_map().tobytes(), b.heaviest_map().tobytes())
        self.assertEqual(a.mean_pose(), b.mean_pose())

    def test_step_by_step_equals_run(self):
        one = grove.FootSlam(SMALL)
        for t, dx, dy in self.walk:
            one.step(t, dx, dy)
        self.assertEqual(one.steps, len(self.walk))
        self.assertSameFilter(one, self.run_walk())
        columns = grove.FootSlam(SMALL)
        columns.run(self.walk[:, 0], self.walk[:, 1], self.walk[:, 2])
        self.assertSameFilter(one, columns)
        lists = grove.FootSlam(SMALL)
        lists.run(self.walk.tolist())
        self.assertSameFilter(one, lists)

    def test_threads_do_not_change_results(self):
        self.assertSameFilter(self.run_walk(), self.run_walk(threads=2, batch=16))

    def test_trajectories_and_poses(self):
        f = grove.FootSlam(SMALL)
        f.set_start_time(0.0)
        f.run(self.walk)
        mean = f.mean_trajectory()
        self.assertEqual(mean.shape, (len(self.walk) + 1, 4))
        self.assertEqual(mean.dtype, np.float64)
        np.testing.assert_array_equal(mean[0], [0, 0, 0, 0])
        np.testing.assert_array_equal(mean[1:, 0], self.walk[:, 0])
        heaviest = f.heaviest_trajectory()
        self.assertEqual(heaviest.shape, mean.shape)
        np.testing.assert_array_equal(heaviest[:, 0], mean[:, 0])
        pose = f.mean_pose()
        self.assertIsInstance(pose, grove.Pose)
        self.assertEqual(tuple(pose), tuple(mean[-1, 1:]))
        # The path history keeps single precision; the current pose is double.
        np.testing.assert_allclose(f.heaviest_pose(), heaviest[-1, 1:], rtol=1e-6, atol=1e-6)
        # Three loops of a closed square end near the start.
        self.assertLess(math.hypot(pose.x, pose.y), 3.0)
        # The smoothed path: the same times, ending at the mean pose (single-precision history).
        smoothed = f.smoothed_trajectory()
        self.assertEqual(smoothed.shape, mean.shape)
        np.testing.assert_array_equal(smoothed[:, 0], mean[:, 0])
        np.testing.assert_allclose(smoothed[-1, 1:3], mean[-1, 1:3], rtol=0, atol=1e-4)

    def test_maps(self):
        f = self.run_walk()
        for m in (f.cumulative_map(), f.heaviest_map()):
            self.assertEqual(m.dtype, grove.HEX_DTYPE)
            self.assertEqual(m.dtype.names, ("q", "r", "x", "y", "counts"))
            self.assertEqual(m.dtype["q"], np.int32)
            self.assertEqual(m.dtype["r"], np.int32)
            self.assertEqual(m.dtype["x"], np.float64)
            self.assertEqual(m["counts"].shape, (len(m), 6))
            self.assertGreater(len(m), 10)
            self.assertTrue(np.all(m["counts"] >= 0))
            self.assertTrue(np.all(m["counts"].sum(axis=1) > 0))
            # Keys are distinct, centres finite and near the walk.
            self.assertEqual(len(set(zip(m["q"].tolist(), m["r"].tolist()))), len(m))
            self.assertTrue(np.all(np.abs(m["x"]) < 20) and np.all(np.abs(m["y"]) < 20))
        heaviest = f.heaviest_map()
        np.testing.assert_array_equal(heaviest["counts"], np.round(heaviest["counts"]))
        # One count per edge crossing, and a 0.7 m step crosses few edges of 0.5 m hexagons.
        self.assertLessEqual(heaviest["counts"].sum(), 6 * len(self.walk))

    def test_arrays_are_copies_that_outlive_the_filter(self):
        f = grove.FootSlam(SMALL)
        f.run(self.walk[:40])
        mean = f.mean_trajectory()
        cmap = f.cumulative_map()
        saved_mean, saved_map = mean.copy(), cmap.copy()
        f.run(self.walk[40:])
        self.assertEqual(mean.shape[0], 41)
        np.testing.assert_array_equal(mean, saved_mean)
        self.assertEqual(cmap.tobytes(), saved_map.tobytes())
        self.assertTrue(mean.flags.owndata and mean.flags.writeable)
        mean[:] = 0  # the caller's to change
        self.assertNotEqual(f.mean_trajectory()[-1, 0], 0)
        del f
        np.testing.assert_array_equal(cmap["q"], saved_map["q"])

    def test_checkpoint_resume_continue_equals_uninterrupted(self):
        whole = self.run_walk()
        half = len(self.walk) // 2
        first = grove.FootSlam(SMALL)
        first.run(self.walk[:half])
        data = first.checkpoint(b"position=%d" % half)
        self.assertIsInstance(data, bytes)
        resumed = grove.FootSlam.resume(data, SMALL, threads=2)  # threads may differ
        self.assertEqual(resumed.user_data, b"position=%d" % half)
        self.assertEqual(resumed.steps, half)
        resumed.run(self.walk[half:])
        self.assertSameFilter(resumed, whole)
        resumed.check_invariants()
        # The checkpointed filter itself goes on unchanged.
        first.run(self.walk[half:])
        self.assertSameFilter(first, whole)

    def test_resume_errors(self):
        f = grove.FootSlam(SMALL)
        f.run(self.walk[:20])
        data = f.checkpoint()
        with self.assertRaisesRegex(grove.FailedPreconditionError, "seed"):
            grove.FootSlam.resume(data, SMALL, seed=8)
        corrupt = bytearray(data)
        corrupt[len(corrupt) // 2] ^= 0xFF
        with self.assertRaises(grove.DataLossError):
            grove.FootSlam.resume(bytes(corrupt), SMALL)
        with self.assertRaises(grove.DataLossError):
            grove.FootSlam.resume(data[: len(data) // 3], SMALL)

    def test_pickle_round_trip_at_every_protocol(self):
        # Regression: protocols 0 and 1 aborted the interpreter.
        for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
            with self.subTest(protocol=protocol):
                f = grove.FootSlam(SMALL)
                f.run(self.walk[:50])
                g = pickle.loads(pickle.dumps(f, protocol=protocol))
                self.assertEqual(g.config, f.config)
                f.run(self.walk[50:])
                g.run(self.walk[50:])
                self.assertSameFilter(f, g)

    def test_init_or_setstate_on_a_live_filter_raises(self):
        # Regression: both silently did nothing.
        f = grove.FootSlam(SMALL)
        f.run(self.walk[:10])
        with self.assertRaisesRegex(TypeError, "already initialised"):
            f.__init__(SMALL, seed=9)
        with self.assertRaisesRegex(TypeError, "already initialised"):
            f.__setstate__(f.__getstate__())
        self.assertEqual(f.config["seed"], SMALL["seed"])
        self.assertEqual(f.steps, 10)
        # A state from __getstate__ still rebuilds a new object (older pickles).
        g = grove.FootSlam.__new__(grove.FootSlam)
        g.__setstate__(f.__getstate__())
        self.assertEqual(g.steps, 10)

    def test_config_as_json_text_raises_type_error(self):
        with self.assertRaisesRegex(TypeError, "json.loads"):
            grove.FootSlam('{"particles": 10}')

    def test_prior_map_of_plain_numbers_raises_type_error(self):
        with self.assertRaisesRegex(TypeError, "HEX_DTYPE.*float64"):
            grove.FootSlam(SMALL).set_prior_map(np.zeros(3))

    def test_complex_or_text_steps_raise_type_error(self):
        f = grove.FootSlam(SMALL)
        with self.assertRaisesRegex(TypeError, "complex128"):
            f.run(np.array([[0.5 + 1j, 0.7, 0.0]]))
        with self.assertRaisesRegex(TypeError, "real numbers"):
            f.run([["0.5", "0.7", "0.0"]])
        self.assertEqual(f.steps, 0)

    def test_summary(self):
        f = self.run_walk()
        s = f.summary()
        self.assertEqual(s["steps"], len(self.walk))
        self.assertEqual(s["particles"], SMALL["particles"])
        self.assertEqual(s["threads_used"], 1)
        self.assertGreater(s["mean_ess"], 0)
        self.assertGreater(s["map_memory"]["live_nodes"], 0)
        self.assertIsInstance(s["report"], str)
        self.assertIn("200 particles", s["report"])

    def test_prior_map_from_an_earlier_walk(self):
        prior = self.run_walk(square_walk(seed=4)).cumulative_map()
        f = grove.FootSlam(SMALL)
        bad = prior.copy()
        bad["counts"][2, 1] = -1.0
        with self.assertRaisesRegex(grove.InvalidArgumentError, "prior map row 2 "):
            f.set_prior_map(bad)
        with self.assertRaises(TypeError):
            f.set_prior_map(np.zeros((2, 2)))
        with self.assertRaisesRegex(ValueError, "one-dimensional"):
            f.set_prior_map(np.stack([prior, prior]))
        f.set_prior_map(prior)
        self.assertEqual(f.summary()["prior_hexagons"], len(prior))
        f.run(self.walk)
        self.assertNotEqual(f.mean_pose(), self.run_walk().mean_pose())
        with self.assertRaises(grove.FailedPreconditionError):
            f.set_prior_map(prior)
        # Confidence 0: the results of no prior, bit for bit.
        g = grove.FootSlam(SMALL, prior_map_confidence=0)
        g.set_prior_map(prior)
        g.run(self.walk)
        self.assertSameFilter(g, self.run_walk())

    def test_storage_of_diversity_stores_areas_left_behind(self):
        # Out 40 m and back: the start's area is stored on the way out, and the return is
        # weighted by the stored map.
        walk = np.array([(0.5 * (k + 1), 0.7 if k < 60 else -0.7, 0.0) for k in range(120)])
        f = grove.FootSlam(SMALL, store_distance_m=10)
        self.assertEqual(len(f.stored_map()), 0)
        f.run(walk)
        s = f.summary()
        self.assertGreater(s["stored_blocks"], 0)
        self.assertEqual(s["stored_hexagons"], len(f.stored_map()))
        self.assertGreater(s["stored_hexagons"], 0)
        self.assertEqual(f.stored_map().dtype, f.cumulative_map().dtype)

    def test_non_finite_step_raises_and_changes_nothing(self):
        f = grove.FootSlam(SMALL)
        f.run(self.walk[:5])
        before = f.mean_trajectory()
        with self.assertRaisesRegex(grove.InvalidArgumentError, "must be finite"):
            f.step(10.0, float("nan"), 0.0)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "must be finite"):
            f.step(float("inf"), 0.1, 0.0)
        self.assertEqual(f.steps, 5)
        np.testing.assert_array_equal(f.mean_trajectory(), before)
        f.step(10.0, 0.5, 0.0)  # still usable
        self.assertEqual(f.steps, 6)

    def test_steps_outside_the_input_bounds_raise_and_change_nothing(self):
        # Regression: FootSLAM took any finite time and step.
        f = grove.FootSlam(SMALL)
        f.run(self.walk[:5])
        before = f.mean_trajectory()
        with self.assertRaisesRegex(grove.InvalidArgumentError, r"dx = 10000000: must be within"):
            f.step(10.0, 1e7, 0.0)
        with self.assertRaisesRegex(grove.InvalidArgumentError, r"t = 1e\+300: must be within"):
            f.step(1e300, 0.1, 0.0)
        self.assertEqual(f.steps, 5)
        np.testing.assert_array_equal(f.mean_trajectory(), before)
        f.step(10.0, 0.5, 0.0)

    def test_time_going_backwards_raises_naming_it(self):
        f = grove.FootSlam(SMALL)
        f.step(1.0, 0.5, 0.0)
        with self.assertRaisesRegex(grove.InvalidArgumentError,
                                    r"t = 0.5 is not after the previous time 1"):
            f.step(0.5, 0.5, 0.0)
        with self.assertRaisesRegex(grove.FailedPreconditionError, "."):
            f.set_start_time(0.0)

    def test_run_stops_at_the_bad_row_and_names_it(self):
        steps = self.walk[:20].copy()
        steps[12, 0] = steps[11, 0]  # time not after the previous one
        f = grove.FootSlam(SMALL)
        with self.assertRaisesRegex(grove.InvalidArgumentError,
                                    r"^row 12 \(t = 6\.?0*\): step 13: .*not after"):
            f.run(steps)
        self.assertEqual(f.steps, 12)  # the rows before it stay applied
        steps = self.walk[:20].copy()
        steps[3, 2] = np.nan
        g = grove.FootSlam(SMALL)
        with self.assertRaisesRegex(grove.InvalidArgumentError, r"^row 3 .*must be finite"):
            g.run(steps)
        self.assertEqual(g.steps, 3)

    def test_run_checks_shapes(self):
        f = grove.FootSlam(SMALL)
        with self.assertRaisesRegex(grove.InvalidArgumentError, r"expected shape \(n, 3\)"):
            f.run(np.zeros((4, 2)))
        with self.assertRaisesRegex(grove.InvalidArgumentError, "lengths 3, 2 and 3"):
            f.run(np.arange(3.0), np.zeros(2), np.zeros(3))
        with self.assertRaises(TypeError):
            f.run(np.arange(3.0), np.zeros(3))
        with self.assertRaises(TypeError):
            f.run("abc")
        f.run(np.empty((0, 3)))
        self.assertEqual(f.steps, 0)

    def test_two_filters_in_two_threads_equal_sequential_runs(self):
        seeds = (11, 12)
        sequential = []
        for seed in seeds:
            f = grove.FootSlam(SMALL, seed=seed)
            f.run(self.walk)
            sequential.append(f)
        parallel = [grove.FootSlam(SMALL, seed=seed) for seed in seeds]
        errors = []

        def work(f):
            try:
                f.run(self.walk)
            except Exception as e:  # reported below
                errors.append(e)

        threads = [threading.Thread(target=work, args=(f,)) for f in parallel]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        self.assertEqual(errors, [])
        for a, b in zip(sequential, parallel):
            self.assertSameFilter(a, b)
        self.assertFalse(np.array_equal(sequential[0].mean_trajectory(),
                                        sequential[1].mean_trajectory()))

    def test_run_releases_the_gil(self):
        # While another thread is inside run(), this thread keeps executing Python: it leaves
        # timestamps well inside the run's interval (impossible if run() held the GIL).
        f = grove.FootSlam(particles=3000, seed=1, threads=1)
        steps = load_walk()
        span = []

        def work():
            span.append(time.monotonic())
            f.run(steps)
            span.append(time.monotonic())

        worker = threading.Thread(target=work)
        stamps = []
        worker.start()
        while worker.is_alive():
            stamps.append(time.monotonic())
            time.sleep(0.001)
        worker.join()
        start, end = span
        margin = 0.2 * (end - start)
        inside = [s for s in stamps if start + margin < s < end - margin]
        self.assertGreater(len(inside), 0, "no Python ran during %.3f s of run()" % (end - start))

    @unittest.skipUnless(signal.getsignal(signal.SIGINT) is signal.default_int_handler,
                         "SIGINT is not Python's KeyboardInterrupt here")
    def test_ctrl_c_stops_a_long_run_between_steps(self):
        f = grove.FootSlam(particles=20000, seed=1, threads=1)
        steps = load_walk()
        timer = threading.Timer(0.2, os.kill, (os.getpid(), signal.SIGINT))
        timer.start()
        try:
            with self.assertRaises(KeyboardInterrupt):
                f.run(steps)  # about 4 s uninterrupted
        finally:
            timer.cancel()
        self.assertLess(f.steps, len(steps))
        f.check_invariants()
        done = f.steps
        f.run(steps[done:done + 5])  # still usable: goes on where it stopped
        self.assertEqual(f.steps, done + 5)

    def test_calls_on_one_filter_from_two_threads_serialise(self):
        f = grove.FootSlam(SMALL)
        stop = threading.Event()
        seen = []

        def reader():
            while not stop.is_set():
                seen.append(f.steps)
                f.mean_pose()

        t = threading.Thread(target=reader)
        t.start()
        try:
            for k in range(0, len(self.walk), 10):
                f.run(self.walk[k:k + 10])
        finally:
            stop.set()
            t.join()
        self.assertSameFilter(f, self.run_walk())
        self.assertEqual(seen, sorted(seen))  # never a step count going back

    def test_bundled_walk(self):
        steps = load_walk()
        self.assertEqual(steps.shape[1], 3)
        f = grove.FootSlam(particles=500, seed=1, threads=2)
        f.run(steps)
        self.assertEqual(f.steps, len(steps))
        mean = f.mean_trajectory()
        self.assertEqual(mean.shape, (len(steps) + 1, 4))
        self.assertTrue(np.all(np.isfinite(mean)))
        m = f.cumulative_map()
        self.assertGreater(len(m), 100)
        self.assertTrue(np.all(m["counts"] >= 0))
        f.check_invariants()
        # Compared with the walk's truth (beside the steps file): the mean path stays close.
        truth_path = WALK_STEPS.replace("_steps.csv", "_truth.csv")
        if os.path.exists(truth_path):
            truth = np.loadtxt(truth_path, delimiter=",", skiprows=1, ndmin=2)
            self.assertEqual(len(truth), len(mean))
            error = np.hypot(mean[:, 1] - truth[:, 1], mean[:, 2] - truth[:, 2])
            self.assertLess(np.sqrt(np.mean(error ** 2)), 5.0)  # 1.4 m measured


def wrap(angle):
    return (angle + math.pi) % (2 * math.pi) - math.pi


def circle_scenario(seconds=20.0, dt=0.025, scan_every=8, seed=5):
    """Bailey's vehicle driving a circle of radius 15 m among 12 landmarks, with the filter's
    Euler steps; detections within 30 m in front carry their landmark's id (known association).
    Returns controls (m, 3), detections (k, 4), the true landmarks (12, 2) and the true final
    pose."""
    rng = np.random.default_rng(seed)
    wheelbase, speed, radius = 4.0, 3.0, 15.0
    steer = math.asin(wheelbase / radius)
    angles = np.arange(6) * (math.pi / 3)
    landmarks = np.concatenate([
        np.stack([8 * np.cos(angles), 15 + 8 * np.sin(angles)], axis=1),
        np.stack([22 * np.cos(angles + 0.5), 15 + 22 * np.sin(angles + 0.5)], axis=1)])
    n = int(round(seconds / dt))
    controls = np.empty((n, 3))
    detections = []
    x = y = phi = 0.0
    for k in range(n):
        t = k * dt
        if k > 0:  # predict from the previous control's time with the held control
            x += speed * dt * math.cos(steer + phi)
            y += speed * dt * math.sin(steer + phi)
            phi = wrap(phi + speed * dt * math.sin(steer) / wheelbase)
        controls[k] = (t, speed, steer)
        if k > 0 and k % scan_every == 0:
            for i, (lx, ly) in enumerate(landmarks):
                r = math.hypot(lx - x, ly - y)
                b = wrap(math.atan2(ly - y, lx - x) - phi)
                if r < 30 and abs(b) < math.pi / 2:
                    detections.append((t, r + rng.normal(0, 0.05),
                                       wrap(b + rng.normal(0, 0.005)), i))
    return controls, np.array(detections), landmarks, (x, y, phi)


class FastSlamTest(unittest.TestCase):
    CONFIG = {"particles": 50, "seed": 3, "threads": 1}

    @classmethod
    def setUpClass(cls):
        cls.controls, cls.detections, cls.landmarks, cls.final = circle_scenario()

    def feed(self, f):
        """The scenario call by call, as run() orders it."""
        z = 0
        d = self.detections
        for k, (t, v, g) in enumerate(self.controls):
            f.control(t, v, g)
            upper = self.controls[k + 1, 0] if k + 1 < len(self.controls) else math.inf
            while z < len(d) and d[z, 0] < upper:
                t_scan = d[z, 0]
                rows = d[z:][d[z:, 0] == t_scan]
                f.scan(t_scan, rows[:, 1:])
                z += len(rows)

    def test_known_association_maps_the_landmarks(self):
        f = grove.FastSlam(self.CONFIG)
        f.run(self.controls, self.detections)
        s = f.summary()
        self.assertEqual(s["controls"], len(self.controls))
        self.assertGreater(s["scans"], 50)
        self.assertEqual(s["observations"], len(self.detections))
        lm = f.landmarks()
        self.assertEqual(lm.dtype, grove.LANDMARK_DTYPE)
        self.assertEqual(lm.dtype.names, ("id", "x", "y", "sxx", "sxy", "syy", "source_id"))
        seen = sorted(set(self.detections[:, 3].astype(int).tolist()))
        self.assertEqual(lm["id"].tolist(), seen)
        self.assertEqual(s["landmarks"], len(seen))
        error = np.hypot(lm["x"] - self.landmarks[lm["id"], 0],
                         lm["y"] - self.landmarks[lm["id"], 1])
        self.assertLess(error.max(), 1.5, error)
        self.assertTrue(np.all(lm["sxx"] > 0) and np.all(lm["syy"] > 0))
        pose = f.mean_pose()
        self.assertLess(math.hypot(pose.x - self.final[0], pose.y - self.final[1]), 1.5)
        self.assertLess(abs(wrap(pose.heading - self.final[2])), 0.1)
        cov = f.pose_covariance()
        self.assertEqual(cov.shape, (3, 3))
        np.testing.assert_array_equal(cov, cov.T)
        self.assertTrue(np.all(np.diag(cov) >= 0))
        mean = f.mean_trajectory()
        self.assertEqual(mean.shape, (f.steps + 1, 4))
        self.assertEqual(f.heaviest_trajectory().shape, mean.shape)
        f.check_invariants()

    def test_call_by_call_equals_run(self):
        a = grove.FastSlam(self.CONFIG)
        a.run(self.controls, self.detections)
        b = grove.FastSlam(self.CONFIG)
        self.feed(b)
        np.testing.assert_array_equal(a.mean_trajectory(), b.mean_trajectory())
        np.testing.assert_array_equal(a.heaviest_trajectory(), b.heaviest_trajectory())
        self.assertEqual(a.landmarks().tobytes(), b.landmarks().tobytes())

    def test_checkpoint_resume_and_repr(self):
        whole = grove.FastSlam(self.CONFIG)
        whole.run(self.controls, self.detections)
        half = len(self.controls) // 2
        t_half = self.controls[half, 0]
        first = grove.FastSlam(self.CONFIG)
        first.run(self.controls[:half], self.detections[self.detections[:, 0] < t_half])
        resumed = grove.FastSlam.resume(first.checkpoint(), self.CONFIG)
        resumed.run(self.controls[half:], self.detections[self.detections[:, 0] >= t_half])
        np.testing.assert_array_equal(resumed.mean_trajectory(), whole.mean_trajectory())
        self.assertEqual(resumed.landmarks().tobytes(), whole.landmarks().tobytes())
        self.assertEqual(repr(whole), "grove.FastSlam(particles=50, seed=3, threads=1)")
        self.assertEqual(grove.FastSlam(filter="fastslam1").config["filter"], "fastslam1")
        jcbb = grove.FastSlam(association="jcbb")
        self.assertEqual(jcbb.config["association"], "jcbb")
        self.assertEqual(jcbb.summary()["association"]["truncated"], 0)

    def test_errors(self):
        f = grove.FastSlam(self.CONFIG)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "control"):
            f.scan(0.0, [[5.0, 0.1, 0]])  # before the first control
        f.control(0.0, 3.0, 0.0)
        # Known association needs ids: the (n, 2) form gives -1, which the engine refuses.
        with self.assertRaisesRegex(grove.InvalidArgumentError, "id"):
            f.scan(0.1, np.array([[5.0, 0.1]]))
        with self.assertRaisesRegex(grove.InvalidArgumentError, "row 0: id = 1.5"):
            f.scan(0.1, np.array([[5.0, 0.1, 1.5]]))
        with self.assertRaisesRegex(grove.InvalidArgumentError, r"expected shape \(n, 2 or 3\)"):
            f.scan(0.1, np.zeros((2, 5)))
        with self.assertRaises(grove.InvalidArgumentError):
            f.control(0.05, float("nan"), 0.0)
        with self.assertRaises(grove.InvalidArgumentError):
            f.control(-1.0, 3.0, 0.0)
        f.scan(0.1, np.array([[5.0, 0.1, 0]]))
        f.scan(0.2, np.empty((0, 2)))  # a scan without detections
        with self.assertRaisesRegex(grove.InvalidArgumentError, "unknown key"):
            grove.FastSlam(wheel_base=3)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "association"):
            grove.FastSlam(association="magic")

    def test_values_outside_the_input_bounds_raise_and_change_nothing(self):
        # Regression: a huge finite range made a landmark of infinite covariance, a control at
        # t = 1e300 blocked every later call, and any speed, steering angle or id passed.
        f = grove.FastSlam(self.CONFIG)
        f.control(0.0, 3.0, 0.0)
        f.scan(0.1, np.array([[5.0, 0.1, 0]]))
        steps, before = f.steps, f.mean_trajectory()
        refused = [
            (lambda: f.scan(0.2, np.array([[1e300, 0.1, 0]])),
             r"observation 0: range = 1e\+300: must be in \[0, 1e6\] m"),
            (lambda: f.scan(0.2, np.array([[1e12, 0.1, 0]])), "range = "),
            (lambda: f.scan(0.2, np.array([[5.0, 0.1, 2.0**40]])), "id = 1099511627776"),
            (lambda: f.control(1e300, 3.0, 0.0), r"t = 1e\+300: must be within \+-1e12 s"),
            (lambda: f.control(0.15, 1e30, 0.0), r"speed = 1e\+30: must be within \+-1000 m/s"),
            (lambda: f.control(0.15, 3.0, 4.0), r"steering = 4: must be in \(-pi/2, pi/2\) rad"),
        ]
        for call, message in refused:
            with self.assertRaisesRegex(grove.InvalidArgumentError, message):
                call()
        self.assertEqual(f.steps, steps)
        np.testing.assert_array_equal(f.mean_trajectory(), before)
        f.control(0.15, 3.0, 0.1)  # not stopped: the next good calls work
        f.scan(0.2, np.array([[5.0, 0.1, 0]]))


class InterpreterErrorTest(unittest.TestCase):
    """An interpreter that cannot use the module is told which one it was built for."""

    def built_for(self):
        return "built for Python %d.%d (" % sys.version_info[:2]

    def test_without_numpy_the_import_error_names_the_interpreter_built_for(self):
        code = ("import sys; sys.path = [p for p in sys.path if 'packages' not in p]; "
                "sys.path.insert(0, %r); import grove" % os.path.dirname(grove.__file__))
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("numpy cannot be imported", r.stderr)
        self.assertIn(self.built_for(), r.stderr)

    def test_another_abi_gets_the_fallback_naming_the_interpreter_built_for(self):
        fallback = os.path.join(os.path.dirname(grove.__file__), "grove.py")
        with tempfile.TemporaryDirectory() as d:
            shutil.copy(fallback, d)  # the module beside it is what another ABI cannot load
            r = subprocess.run([sys.executable, "-B", "-c", "import grove"], cwd=d,
                               capture_output=True, text=True)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("the extension module in this directory was " + self.built_for(), r.stderr)


if __name__ == "__main__":
    unittest.main()
