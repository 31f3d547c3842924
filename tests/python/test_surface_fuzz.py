"""Random calls on the grove Python module's whole surface: no input crashes the interpreter, and
every refusal is one of the documented exceptions (a grove error, TypeError, ValueError,
OverflowError). A fixed seed, so a failure repeats; the failing call is printed.

Run from a build: ctest -R python_test (it runs with test_grove), or by hand with the module's
directory on PYTHONPATH: PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_surface_fuzz
"""

import math
import pickle
import random
import unittest

import numpy as np

import grove

ALLOWED = (grove.GroveError, TypeError, ValueError, OverflowError)
SEED = 20261206
CALLS = 3000


def random_value(rng, depth=0):
    """Anything a careless caller might pass: numbers of every kind, text, containers, arrays of
    odd shapes and dtypes."""
    kinds = ["none", "bool", "int", "big", "float", "special", "complex", "str", "bytes", "list",
             "dict", "array", "empty", "object"]
    kind = rng.choice(kinds if depth < 2 else kinds[:8])
    if kind == "none":
        return None
    if kind == "bool":
        return rng.random() < 0.5
    if kind == "int":
        return rng.randint(-5, 300)
    if kind == "big":
        return rng.choice([2**31, 2**63, -2**63 - 1, 2**64, 10**30])
    if kind == "float":
        return rng.uniform(-10, 10)
    if kind == "special":
        return rng.choice([math.nan, math.inf, -math.inf, 1e300, -0.0, 5e-324])
    if kind == "complex":
        return complex(rng.uniform(-1, 1), rng.uniform(-1, 1))
    if kind == "str":
        return rng.choice(["", "a", "1.5", "particles", "fastslam2", "\x00", "é" * 70])
    if kind == "bytes":
        return bytes(rng.randrange(256) for _ in range(rng.randrange(40)))
    if kind == "list":
        return [random_value(rng, depth + 1) for _ in range(rng.randrange(4))]
    if kind == "dict":
        keys = ["particles", "seed", "threads", "filter", "nope", "hex_radius_m", 3]
        return {rng.choice(keys): random_value(rng, depth + 1) for _ in range(rng.randrange(3))}
    if kind == "array":
        shape = tuple(rng.randrange(0, 5) for _ in range(rng.randrange(0, 4)))
        dtype = rng.choice([np.float64, np.float32, np.int64, np.uint8, np.bool_, np.complex128,
                            np.object_])
        a = np.asarray(np.random.default_rng(rng.randrange(1 << 30)).normal(size=shape))
        if dtype is np.object_:
            return a.astype(object)
        return a.astype(dtype)
    if kind == "empty":
        return np.empty((0, rng.randrange(0, 5)))
    return object()


class SurfaceFuzzTest(unittest.TestCase):
    def call(self, what, fn, *args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except ALLOWED:
            return None
        except Exception as e:  # pylint: disable=broad-except
            self.fail("%s(%r, %r) raised %s: %s" % (what, args, kwargs, type(e).__name__, e))

    def test_random_calls_raise_only_documented_errors(self):
        rng = random.Random(SEED)
        filters = [grove.FootSlam(particles=20, threads=1), grove.FastSlam(particles=10, threads=1)]
        foot_methods = ["step", "run", "set_start_time", "set_prior_map", "checkpoint",
                        "mean_pose", "cumulative_map", "smoothed_trajectory", "stored_map"]
        fast_methods = ["control", "scan", "run", "checkpoint", "landmarks", "pose_covariance",
                        "mean_pose", "heaviest_trajectory"]
        statics = [(grove.FootSlam, "resume"), (grove.FastSlam, "resume"),
                   (grove.FootSlam, "estimate_peak_bytes"), (grove.FootSlam, None),
                   (grove.FastSlam, None)]
        for k in range(CALLS):
            args = [random_value(rng) for _ in range(rng.randrange(0, 4))]
            choice = rng.random()
            if choice < 0.15:
                cls, name = rng.choice(statics)
                kwargs = random_value(rng) if rng.random() < 0.3 else {}
                kwargs = kwargs if isinstance(kwargs, dict) else {}
                kwargs = {str(key): v for key, v in kwargs.items()}
                fn = cls if name is None else getattr(cls, name)
                made = self.call("%s.%s" % (cls.__name__, name), fn, *args, **kwargs)
                if isinstance(made, (grove.FootSlam, grove.FastSlam)):
                    for protocol in (0, 2, pickle.HIGHEST_PROTOCOL):
                        pickle.loads(pickle.dumps(made, protocol=protocol))
                continue
            f = rng.choice(filters)
            names = foot_methods if isinstance(f, grove.FootSlam) else fast_methods
            name = rng.choice(names)
            self.call("%s.%s #%d" % (type(f).__name__, name, k), getattr(f, name), *args)
        # The filters still answer after all that.
        for f in filters:
            f.check_invariants()
            self.assertEqual(len(f.mean_pose()), 3)


if __name__ == "__main__":
    unittest.main()
