"""A plain reference of grove's foot IMU front end (engine/imu/): the same zero-velocity-aided
INS written directly from the equations with numpy, for test_foot_imu_reference.py to hold the
C++ one against. It processes a whole recording at once; only the SHOE detector.

Frames and equations as engine/imu/README.md states them: navigation frame x, y level, z up,
gravity (0, 0, -g); C the sensor-to-navigation rotation; error state (19) position, velocity,
attitude (C_true = (I + [dtheta x]) C), accelerometer bias, gyroscope bias, and the clone of
position and heading at the last stance end; errors are true minus estimate.
"""

import math

import numpy as np

STATES = 19
P, V, TH, BA, BG, CL = 0, 3, 6, 9, 12, 15
ZARU_GATE = 16.27  # chi-square, 3 degrees of freedom, 0.1 %


def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def exp_so3(phi):
    """The rotation matrix of the rotation vector phi (Rodrigues)."""
    angle = np.linalg.norm(phi)
    if angle < 1e-12:
        return np.eye(3) + skew(phi)
    k = skew(phi / angle)
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def normal_gravity(latitude_deg, height_m):
    s2 = math.sin(math.radians(latitude_deg)) ** 2
    return (9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - 0.00669437999013 * s2)
            - 3.086e-6 * height_m)


def heading_of(c):
    return math.atan2(c[1, 0], c[0, 0])


def heading_jacobian(c):
    den = c[0, 0] ** 2 + c[1, 0] ** 2
    return np.array([-c[0, 0] * c[2, 0] / den, -c[1, 0] * c[2, 0] / den, 1.0])


def wrap(a):
    a = math.remainder(a, 2 * math.pi)
    return a + 2 * math.pi if a <= -math.pi else a


def shoe_still(accel, gyro, window, threshold, sigma_a, sigma_w, g, gap):
    """Each sample's zero-velocity decision: SHOE on a centred window, cut at the ends, then
    moving runs of at most `gap` samples between still ones made still."""
    n = len(accel)
    before, after = (window - 1) // 2, window // 2
    raw = np.zeros(n, bool)
    for k in range(n):
        a = accel[max(0, k - before):min(n, k + after + 1)]
        w = gyro[max(0, k - before):min(n, k + after + 1)]
        mean = a.mean(axis=0)
        up = g * mean / np.linalg.norm(mean)
        t = (np.sum((a - up) ** 2) / sigma_a ** 2 + np.sum(w ** 2) / sigma_w ** 2) / len(a)
        raw[k] = t < threshold
    still = raw.copy()
    k = 0
    while k < n:
        if raw[k]:
            k += 1
            continue
        end = k
        while end < n and not raw[end]:
            end += 1
        if k > 0 and end < n and end - k <= gap:
            still[k:end] = True
        k = end
    return still


class Filter:
    """The nominal state and the error-state Kalman filter with its clone."""

    def __init__(self, c, gyro_bias, cfg, g):
        self.cfg, self.g = cfg, g
        self.p = np.zeros(3)
        self.v = np.zeros(3)
        self.c = c
        self.ba = np.zeros(3)
        self.bg = gyro_bias.copy()
        self.cov = np.zeros((STATES, STATES))
        self.cov[V:V + 3, V:V + 3] = np.eye(3) * cfg["zupt_sigma_mps"] ** 2
        self.cov[TH, TH] = self.cov[TH + 1, TH + 1] = cfg["alignment_tilt_sigma_rad"] ** 2
        self.cov[TH + 2, TH + 2] = cfg["alignment_heading_sigma_rad"] ** 2
        self.cov[BA:BA + 3, BA:BA + 3] = np.eye(3) * cfg["initial_accel_bias_sigma_mps2"] ** 2
        self.cov[BG:BG + 3, BG:BG + 3] = np.eye(3) * cfg["initial_gyro_bias_sigma_radps"] ** 2
        self.clone()

    def propagate(self, a0, w0, a1, w1, dt):
        w0, w1 = w0 - self.bg, w1 - self.bg
        c0 = self.c
        f0 = c0 @ (a0 - self.ba)
        phi = 0.5 * (w0 + w1) * dt + np.cross(w0, w1) * dt * dt / 12
        self.c = c0 @ exp_so3(phi)
        f1 = self.c @ (a1 - self.ba)
        fn = 0.5 * (f0 + f1)
        v0 = self.v.copy()
        self.v = self.v + (fn + np.array([0, 0, -self.g])) * dt
        self.p = self.p + 0.5 * (v0 + self.v) * dt
        f = np.eye(STATES)
        f[P:P + 3, V:V + 3] = dt * np.eye(3)
        f[V:V + 3, TH:TH + 3] = -dt * skew(fn)
        f[V:V + 3, BA:BA + 3] = -dt * 0.5 * (c0 + self.c)
        f[TH:TH + 3, BG:BG + 3] = -dt * 0.5 * (c0 + self.c)
        q = np.zeros((STATES, STATES))
        cfg = self.cfg
        q[V:V + 3, V:V + 3] = np.eye(3) * cfg["accel_noise_mps2_per_sqrt_hz"] ** 2 * dt
        q[TH:TH + 3, TH:TH + 3] = np.eye(3) * cfg["gyro_noise_radps_per_sqrt_hz"] ** 2 * dt
        q[BA:BA + 3, BA:BA + 3] = np.eye(3) * cfg["accel_bias_walk_mps3_per_sqrt_hz"] ** 2 * dt
        q[BG:BG + 3, BG:BG + 3] = np.eye(3) * cfg["gyro_bias_walk_radps2_per_sqrt_hz"] ** 2 * dt
        self.cov = f @ self.cov @ f.T + q

    def update(self, first, y, r, gate=None):
        h = np.zeros((3, STATES))
        h[:, first:first + 3] = np.eye(3)
        s = h @ self.cov @ h.T + r * np.eye(3)
        s_inv = np.linalg.inv(s)
        if gate is not None and y @ s_inv @ y > gate:
            return
        k = self.cov @ h.T @ s_inv
        self.cov = self.cov - k @ h @ self.cov
        self.cov = 0.5 * (self.cov + self.cov.T)
        dx = k @ y
        self.p = self.p + dx[P:P + 3]
        self.v = self.v + dx[V:V + 3]
        self.c = exp_so3(dx[TH:TH + 3]) @ self.c
        self.ba = self.ba + dx[BA:BA + 3]
        self.bg = self.bg + dx[BG:BG + 3]
        self.clone_p = self.clone_p + dx[CL:CL + 3]
        self.clone_heading += dx[CL + 3]

    def clone(self):
        self.clone_p = self.p.copy()
        self.clone_heading = heading_of(self.c)
        j = np.zeros((4, STATES))
        j[0:3, P:P + 3] = np.eye(3)
        j[3, TH:TH + 3] = heading_jacobian(self.c)
        nav = self.cov.copy()
        nav[CL:, :] = 0
        nav[:, CL:] = 0
        jp = j @ nav
        self.cov[CL:, :] = jp
        self.cov[:, CL:] = jp.T
        self.cov[CL:, CL:] = jp @ j.T

    def since_clone(self):
        d = self.p - self.clone_p
        heading = wrap(heading_of(self.c) - self.clone_heading)
        l = np.zeros((3, STATES))
        l[0, P] = l[1, P + 1] = 1
        l[2, TH:TH + 3] = heading_jacobian(self.c)
        l[0, CL] = l[1, CL + 1] = l[2, CL + 3] = -1
        return d, heading, l @ self.cov @ l.T


def steps(t, accel, gyro, cfg):
    """The steps of a recording: a list of dicts with t, dx, dy, dz, dheading, covariance
    (3 x 3 over dx, dy, dheading), stance_begin and stance_end."""
    g = cfg["gravity_mps2"] or normal_gravity(cfg["latitude_deg"], cfg["height_m"])
    still = shoe_still(accel, gyro, cfg["detector_window"], cfg["detector_threshold"],
                       cfg["detector_accel_sigma_mps2"], cfg["detector_gyro_sigma_radps"], g,
                       cfg["stance_gap_samples"])
    out = []
    flt = None
    run = {"on": False, "begin": 0.0, "end": 0.0, "n": 0}
    sums = [np.zeros(3), np.zeros(3)]
    origin = [False]

    def note_still(k):
        if not run["on"]:
            run.update(on=True, begin=t[k], n=0)
        run["n"] += 1
        run["end"] = t[k]

    def end_run():
        run["on"] = False
        if run["n"] < cfg["min_stance_samples"]:
            return
        mid = 0.5 * (run["begin"] + run["end"])
        if not origin[0]:
            origin[0] = True
            flt.clone()
            return
        d, dh, cov = flt.since_clone()
        if math.hypot(d[0], d[1]) < cfg["min_step_m"]:
            return
        out.append({"t": mid, "dx": d[0], "dy": d[1], "dz": d[2], "dheading": dh,
                    "covariance": cov, "stance_begin": run["begin"], "stance_end": run["end"]})
        flt.clone()

    for k in range(len(t)):
        if flt is None:
            if not still[k]:
                run["on"] = False
                sums = [np.zeros(3), np.zeros(3)]
                continue
            note_still(k)
            sums[0] = sums[0] + accel[k]
            sums[1] = sums[1] + gyro[k]
            if t[k] - run["begin"] < cfg["alignment_s"]:
                continue
            f = sums[0] / run["n"]
            roll = math.atan2(f[1], f[2])
            pitch = math.atan2(-f[0], math.hypot(f[1], f[2]))
            yaw = cfg["alignment_heading_rad"]
            rz = exp_so3(np.array([0, 0, yaw]))
            ry = exp_so3(np.array([0, pitch, 0]))
            rx = exp_so3(np.array([roll, 0, 0]))
            flt = Filter(rz @ ry @ rx, sums[1] / run["n"], cfg, g)
            prev = k
            continue
        if not still[k] and run["on"]:
            end_run()
        flt.propagate(accel[prev], gyro[prev], accel[k], gyro[k], t[k] - t[prev])
        prev = k
        if not still[k]:
            continue
        flt.update(V, -flt.v, cfg["zupt_sigma_mps"] ** 2)
        if cfg["zaru_sigma_radps"] > 0:
            flt.update(BG, gyro[k] - flt.bg, cfg["zaru_sigma_radps"] ** 2, ZARU_GATE)
        note_still(k)
    if run["on"] and flt is not None:
        end_run()
    return out
