"""Tests of grove.Tracker, the beacon tracker's Python class (engine/bindings/python/
tracker_module.cc): the embedder's view.

Run from a build: ctest -R python_test, or by hand with the module's directory on PYTHONPATH:
  PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_tracker
"""

import math
import pickle
import unittest

import numpy as np

import grove

BEACONS = np.array([[-40.0, -40.0], [40.0, -40.0], [40.0, 40.0], [-40.0, 40.0]])


def circle_run(updates=50, noise=0.3, seed=5):
    """A target on a circle of radius 15 m, one update a second with a range to every beacon:
    rows [t, beacon x, beacon y, range] (k, 4), and the truth (updates, 2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(1, updates + 1, dtype=float)
    truth = np.stack([15 * np.sin(0.05 * t), 15 - 15 * np.cos(0.05 * t)], axis=1)
    rows = []
    for k in range(updates):
        for bx, by in BEACONS:
            r = math.hypot(truth[k, 0] - bx, truth[k, 1] - by) + rng.normal(0, noise)
            rows.append([t[k], bx, by, r])
    return np.array(rows), truth


SMALL = {"particles": 1500, "threads": 1, "initial_position_sigma_m": 5}


class TrackerTest(unittest.TestCase):
    def test_follows_a_target_among_beacons(self):
        rows, truth = circle_run()
        t = grove.Tracker(SMALL)
        t.run(rows)
        self.assertEqual(t.steps, 50)
        path = t.mean_trajectory()
        self.assertEqual(path.shape, (51, 4))
        error = np.hypot(path[11:, 1] - truth[10:, 0], path[11:, 2] - truth[10:, 1])
        self.assertLess(error.max(), 1.0)
        x, y, vx, vy = t.mean_state()
        self.assertLess(math.hypot(x - truth[-1, 0], y - truth[-1, 1]), 1.0)
        self.assertAlmostEqual(vx, 0.75 * math.cos(2.5), delta=0.3)
        summary = t.summary()
        self.assertEqual(summary["measurements"], 200)
        self.assertIn("Tracker: 1500 particles", summary["report"])

    def test_update_by_update_and_run_give_the_same_bits_at_any_thread_count(self):
        rows, _ = circle_run(updates=20)
        whole = grove.Tracker(SMALL, threads=2)
        whole.run(rows)
        stepped = grove.Tracker(SMALL)
        for k in range(20):
            stepped.update(rows[4 * k, 0], rows[4 * k:4 * k + 4, 1:])
        np.testing.assert_array_equal(whole.mean_trajectory(), stepped.mean_trajectory())
        self.assertEqual(whole.mean_state(), stepped.mean_state())

    def test_a_bad_range_raises_naming_it_and_changes_nothing(self):
        rows, _ = circle_run(updates=3)
        t = grove.Tracker(SMALL)
        t.update(1.0, rows[0:4, 1:])
        before = t.mean_trajectory()
        bad = rows[4:8, 1:].copy()
        bad[2, 2] = -1
        with self.assertRaises(grove.InvalidArgumentError) as cm:
            t.update(2.0, bad)
        self.assertIn("measurement 2", str(cm.exception))
        with self.assertRaises(grove.InvalidArgumentError):
            t.update(1.0, rows[4:8, 1:])  # not after the previous update
        with self.assertRaises(grove.InvalidArgumentError):
            t.update(2.0, np.zeros((2, 2)))  # not (n, 3)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "times must not decrease"):
            t.run(rows[::-1])
        self.assertEqual(t.steps, 1)
        np.testing.assert_array_equal(t.mean_trajectory(), before)

    def test_checkpoint_resume_and_pickle_continue_bit_for_bit(self):
        rows, _ = circle_run(updates=30)
        whole = grove.Tracker(SMALL)
        whole.run(rows)
        half = grove.Tracker(SMALL)
        half.run(rows[:60])
        resumed = grove.Tracker.resume(half.checkpoint(b"at 15"), SMALL, threads=2)
        self.assertEqual(resumed.user_data, b"at 15")
        unpickled = pickle.loads(pickle.dumps(half, protocol=0))
        for t in (resumed, unpickled):
            t.run(rows[60:])
            np.testing.assert_array_equal(t.mean_trajectory(), whole.mean_trajectory())
        with self.assertRaisesRegex(grove.FailedPreconditionError, "range_sigma_m"):
            grove.Tracker.resume(half.checkpoint(), SMALL, range_sigma_m=0.25)

    def test_configuration_keys_defaults_and_repr(self):
        names = [f["name"] for f in grove.Tracker.config_fields()]
        self.assertEqual(names[:2], ["particles", "seed"])
        self.assertIn("range_sigma_m", names)
        self.assertEqual(grove.Tracker(threads=1).config["particles"], 2000)
        t = grove.Tracker(particles=10, range_sigma_m=0.25, threads=1)
        self.assertEqual(repr(t), "grove.Tracker(particles=10, seed=1, range_sigma_m=0.25, "
                                  "threads=1)")
        with self.assertRaisesRegex(grove.InvalidArgumentError, 'did you mean "range_sigma_m"'):
            grove.Tracker(range_sigma=1)
        self.assertIn("one thread at a time", grove.Tracker.__doc__)


if __name__ == "__main__":
    unittest.main()
