"""grove.FootImu, the foot IMU front end in the Python module: configuration, bad samples, and a
synthetic walk of known steps, also held against the plain reference (foot_imu_reference.py).

Run from a build: ctest -R python_foot_imu_test, or by hand:
  PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_foot_imu
"""

import math
import unittest

import numpy as np

import grove
import foot_imu_reference

RATE_HZ = 200
GRAVITY = 9.80665
STEP_M = 0.7
STEPS = 6


def synthetic_walk(heading_per_step=0.0):
    """Stances of 0.6 s, swings of 0.5 s along the sensor's heading: a minimum-jerk position
    profile over STEP_M while the sensor rolls about its x axis by 0.5 sin^2(pi u) rad and back,
    and turns about z by heading_per_step (minimum-jerk too) during each swing. Rows t, ax, ay,
    az, gx, gy, gz; the steps it makes in the odometry frame."""
    stance, swing = int(0.6 * RATE_HZ), int(0.5 * RATE_HZ)
    rows, truth = [], []
    yaw = 0.0
    for step in range(STEPS + 1):
        moving = step < STEPS
        for k in range(stance + (swing if moving else 0)):
            t = len(rows) / RATE_HZ
            if k < stance:
                rows.append([t, 0, 0, GRAVITY, 0, 0, 0])
                continue
            u = (k - stance) / swing
            s_dd = (60 * u - 180 * u**2 + 120 * u**3) / 0.25  # d2/dt2 of the profile over 0.5 s
            s_d = (30 * u**2 - 60 * u**3 + 30 * u**4) / 0.5
            profile = 10 * u**3 - 15 * u**4 + 6 * u**5
            psi = yaw + heading_per_step * profile
            psi_d = heading_per_step * s_d
            roll = 0.5 * math.sin(math.pi * u) ** 2
            roll_d = 0.5 * math.pi / 0.5 * math.sin(2 * math.pi * u)
            # Straight line along yaw at the step's start (the heading turns in place).
            a_nav = np.array([math.cos(yaw), math.sin(yaw), 0]) * STEP_M * s_dd + [0, 0, GRAVITY]
            cz, sz, cx, sx = math.cos(psi), math.sin(psi), math.cos(roll), math.sin(roll)
            rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
            rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
            c = rz @ rx  # sensor to navigation
            f = c.T @ a_nav
            # The angular rate in the sensor frame: roll_d about x, psi_d about navigation z.
            w = np.array([roll_d, 0, 0]) + rx.T @ np.array([0, 0, psi_d])
            rows.append([t, *f, *w])
        if moving:
            truth.append((STEP_M * math.cos(yaw), STEP_M * math.sin(yaw), heading_per_step))
            yaw += heading_per_step
    return np.array(rows), truth


class FootImuTest(unittest.TestCase):
    def test_a_synthetic_walk_gives_its_true_steps(self):
        samples, truth = synthetic_walk(heading_per_step=math.radians(15))
        steps = grove.foot_imu_steps(samples, gravity_mps2=GRAVITY)
        self.assertEqual(steps.shape, (STEPS, len(grove.FootImu.STEP_COLUMNS)))
        for row, (dx, dy, dh) in zip(steps, truth):
            self.assertAlmostEqual(row[1], dx, delta=0.002)
            self.assertAlmostEqual(row[2], dy, delta=0.002)
            self.assertAlmostEqual(row[4], dh, delta=math.radians(0.01))
            self.assertGreater(row[5], 0)  # var_dx
        self.assertTrue(np.all(np.diff(steps[:, 0]) > 0))

    def test_the_module_and_the_reference_agree(self):
        samples, _ = synthetic_walk(heading_per_step=math.radians(-20))
        config = grove.FootImu.default_config()
        config["gravity_mps2"] = GRAVITY
        ours = grove.foot_imu_steps(samples, config)
        config["detector_threshold"] = 3e4  # the reference takes no default
        theirs = foot_imu_reference.steps(samples[:, 0], samples[:, 1:4], samples[:, 4:7], config)
        self.assertEqual(len(ours), len(theirs))
        for row, ref in zip(ours, theirs):
            self.assertEqual(row[0], ref["t"])
            for col, key in ((1, "dx"), (2, "dy"), (3, "dz"), (4, "dheading")):
                self.assertAlmostEqual(row[col], ref[key], delta=1e-9)
            self.assertAlmostEqual(row[5], ref["covariance"][0, 0], delta=1e-12)

    def test_samples_given_in_pieces_give_the_same_steps(self):
        samples, _ = synthetic_walk()
        whole = grove.foot_imu_steps(samples, gravity_mps2=GRAVITY)
        imu = grove.FootImu(gravity_mps2=GRAVITY)
        pieces = []
        for chunk in np.array_split(samples, 7):
            imu.add_samples(chunk)
            pieces.append(imu.take_steps())
        imu.finish()
        pieces.append(imu.take_steps())
        np.testing.assert_array_equal(np.concatenate(pieces), whole)
        self.assertEqual(imu.take_steps().shape, (0, 13))
        summary = imu.summary()
        self.assertEqual(summary["steps"], STEPS)
        self.assertAlmostEqual(summary["distance"], STEPS * STEP_M, delta=0.03)
        self.assertTrue(imu.state()["still"])

    def test_the_steps_feed_footslam(self):
        samples, _ = synthetic_walk(heading_per_step=math.radians(10))
        steps = grove.foot_imu_steps(samples, gravity_mps2=GRAVITY)
        slam = grove.FootSlam(particles=50, seed=1, threads=1)
        slam.run(steps[:, :3])
        self.assertEqual(slam.steps, STEPS)

    def test_configuration_errors_name_the_key(self):
        with self.assertRaisesRegex(grove.InvalidArgumentError, "detector_window"):
            grove.FootImu(detector_windwo=3)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "zupt_sigma_mps = nan"):
            grove.FootImu(zupt_sigma_mps=float("nan"))
        with self.assertRaisesRegex(grove.InvalidArgumentError, "detector"):
            grove.FootImu(detector="zero")
        with self.assertRaises(TypeError):
            grove.FootImu("shoe")
        self.assertEqual(grove.FootImu({"detector": "are"}, detector_window=9).config["detector"],
                         "are")
        self.assertEqual(grove.FootImu.default_config()["detector"], "shoe")

    def test_a_bad_sample_names_its_row_and_keeps_the_rows_before(self):
        imu = grove.FootImu()
        good = [0.0, 0, 0, GRAVITY, 0, 0, 0]
        with self.assertRaisesRegex(grove.InvalidArgumentError, "row 2: .*not after"):
            imu.add_samples([good, [0.005, *good[1:]], [0.005, *good[1:]]])
        self.assertEqual(imu.summary()["samples"], 2)
        with self.assertRaisesRegex(grove.InvalidArgumentError, "row 0: .*must be finite"):
            imu.add_samples([[0.01, math.nan, 0, GRAVITY, 0, 0, 0]])
        with self.assertRaisesRegex(grove.InvalidArgumentError, "row 0: .*saturated"):
            imu.add_samples([[0.01, 0, 0, GRAVITY, 100, 0, 0]])
        with self.assertRaisesRegex(grove.InvalidArgumentError, "shape"):
            imu.add_samples(np.zeros((3, 6)))
        imu.finish()
        with self.assertRaises(grove.FailedPreconditionError):
            imu.add_samples([[0.02, *good[1:]]])


if __name__ == "__main__":
    unittest.main()
