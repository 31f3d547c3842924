"""grove's foot IMU front end against a plain reference written from the same equations
(foot_imu_reference.py): `grove footslam steps` and the reference read one simulated recording
and must give the same steps.

Run from a build: ctest -R foot_imu_reference_test, or by hand:
  GROVE_BINARY=<build>/tools/grove /usr/bin/python3 -m unittest -v test_foot_imu_reference
"""

import csv
import json
import os
import subprocess
import tempfile
import unittest

import numpy as np

import foot_imu_reference

GROVE = os.environ.get("GROVE_BINARY", "grove")


def grove(*args):
    return subprocess.run([GROVE, *args], check=True, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True).stdout


class ReferenceTest(unittest.TestCase):
    def test_grove_and_the_reference_give_the_same_steps(self):
        with tempfile.TemporaryDirectory() as d:
            # A minute of the building walk with the default (BMI160-like) sensor errors.
            grove("footslam", "simulate", "--minutes", "1", "--seed", "5", "--imu", "--out", d)
            grove("footslam", "steps", "--imu", os.path.join(d, "imu.csv"), "--out",
                  os.path.join(d, "imu_steps.csv"), "--stances", os.path.join(d, "found.csv"),
                  "--no-progress")
            config = json.loads(grove("footslam", "steps", "--imu", os.path.join(d, "imu.csv"),
                                      "--out", os.path.join(d, "unused.csv"), "--print-config"))
            data = np.loadtxt(os.path.join(d, "imu.csv"), delimiter=",", skiprows=1)
            with open(os.path.join(d, "imu_steps.csv")) as f:
                ours = list(csv.DictReader(f))
            with open(os.path.join(d, "found.csv")) as f:
                stances = list(csv.DictReader(f))
        # The reference takes the detector's own default threshold (SHOE: 3e4).
        if config["detector_threshold"] == 0:
            config["detector_threshold"] = 3e4
        self.assertEqual(config["detector"], "shoe")
        theirs = foot_imu_reference.steps(data[:, 0], data[:, 1:4], data[:, 4:7], config)
        self.assertGreater(len(theirs), 20)
        self.assertEqual(len(ours), len(theirs))
        worst = {"position": 0.0, "heading": 0.0, "covariance": 0.0}
        for o, t, s in zip(ours, theirs, stances):
            self.assertEqual(float(o["t"]), t["t"])
            self.assertEqual(float(s["begin"]), t["stance_begin"])
            self.assertEqual(float(s["end"]), t["stance_end"])
            for key in ("dx", "dy", "dz"):
                worst["position"] = max(worst["position"], abs(float(o[key]) - t[key]))
            worst["heading"] = max(worst["heading"], abs(float(o["dheading"]) - t["dheading"]))
            c = t["covariance"]
            for key, value in (("var_dx", c[0, 0]), ("cov_dx_dy", c[0, 1]), ("var_dy", c[1, 1]),
                               ("cov_dx_dheading", c[0, 2]), ("cov_dy_dheading", c[1, 2]),
                               ("var_dheading", c[2, 2])):
                scale = max(c[0, 0], c[2, 2])
                worst["covariance"] = max(worst["covariance"],
                                          abs(float(o[key]) - value) / scale)
        print("largest differences: %s" % worst)
        self.assertLess(worst["position"], 1e-6)
        self.assertLess(worst["heading"], 1e-8)
        self.assertLess(worst["covariance"], 1e-6)


if __name__ == "__main__":
    unittest.main()
