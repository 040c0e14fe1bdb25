"""Base physics of a hand-turned multi-position accelerometer calibration session.

Everything here is the *nominal* session: a MEMS part with its true linear
calibration errors (3x3 sensitivity matrix, zero-g offsets), white noise from its
noise density, ADC quantisation and range clipping, held still in random
orientations and turned by hand between them.  The effects under test are added by
the injectors in `injectors.py`, which write into the `Session` arrays:

* `f`        true specific force at the sensor, sensor axes, in g (N x 3).  Motion and
             mount vibration are physical accelerations and are added here.
* `bias`     additive sensor-output offset beyond the constant zero-g offset, g (N x 3).
* `scale`    fractional sensitivity change per axis, dimensionless (N x 3).
* `nl`       list of callables f(N x 3, g) -> output offset (N x 3, g): non-linear
             transfer of the sensing element (applied to the specific force per axis).
* `noise`    additive sensor noise beyond the white noise, g (N x 3).
* `temp_log` logged temperature column in degC (None: no column).

`render()` turns it into what a logger writes:
    y = M ((1 + scale) * f + nl(f)) + b0 + bias + white + noise,  quantised, clipped.
"""

import math

import numpy as np

G0 = 9.80665  # m/s^2 per g (standard gravity, what an m/s^2 logger multiplies by)

# Datasheet-like MEMS parts.  nd: noise density ug/sqrt(Hz); bw: max analogue/digital
# bandwidth Hz; lsb: g per LSB; bits: output word; b0: zero-g offset tolerance (g, 1
# sigma used as half the datasheet +- figure); sf: sensitivity tolerance (fraction);
# xa: cross-axis sensitivity (fraction); tc_b: zero-g tempco mg/degC; tc_s:
# sensitivity tempco %/degC; nl: non-linearity %FS; fs_g: full scale g; t_lsb:
# temperature sensor resolution degC.
PARTS = {
    # InvenSense MPU-6050 at +-2 g: 16384 LSB/g, 400 ug/rtHz, +-50 mg (X,Y) +-80 mg (Z),
    # +-3 % sensitivity, +-2 % cross-axis, 0.5 % NL, ~0.5-0.9 mg/degC, 0.02 %/degC.
    "mpu6050": dict(nd=400e-6, bw=260.0, lsb=1 / 16384, bits=16, b0=(0.025, 0.025, 0.04),
                    sf=0.015, xa=0.01, tc_b=0.6, tc_s=0.02, nl=0.5, fs_g=2.0, t_lsb=1 / 340),
    # ST LSM6DS3 at +-2 g: 0.061 mg/LSB, 90 ug/rtHz, +-40 mg, +-1 % ..
    "lsm6ds3": dict(nd=90e-6, bw=400.0, lsb=0.061e-3, bits=16, b0=(0.02, 0.02, 0.02),
                    sf=0.01, xa=0.005, tc_b=0.5, tc_s=0.01, nl=0.3, fs_g=2.0, t_lsb=1 / 256),
    # ST LIS3DH high-resolution mode (12 bit): 1 mg/LSB, 220 ug/rtHz, +-40 mg.
    "lis3dh": dict(nd=220e-6, bw=200.0, lsb=1e-3, bits=12, b0=(0.02, 0.02, 0.03),
                   sf=0.02, xa=0.01, tc_b=0.5, tc_s=0.01, nl=0.5, fs_g=2.0, t_lsb=1.0),
    # ADI ADXL345 full-resolution: 3.9 mg/LSB (256 LSB/g): coarse quantisation.
    "adxl345": dict(nd=290e-6, bw=400.0, lsb=3.9e-3, bits=13, b0=(0.02, 0.02, 0.04),
                    sf=0.02, xa=0.01, tc_b=0.8, tc_s=0.01, nl=0.5, fs_g=16.0, t_lsb=0.5),
    # ADI ADXL355: 3.9 ug/LSB (20 bit), 25 ug/rtHz, +-25 mg, 0.1 % NL, 0.15 mg/degC.
    "adxl355": dict(nd=25e-6, bw=1000.0, lsb=3.9e-6, bits=20, b0=(0.0125, 0.0125, 0.0125),
                    sf=0.005, xa=0.005, tc_b=0.15, tc_s=0.01, nl=0.1, fs_g=2.0, t_lsb=1 / 9.05),
    # Bosch BMI160 at +-2 g: 16384 LSB/g, 180 ug/rtHz, +-40 mg, 1 mg/degC.
    "bmi160": dict(nd=180e-6, bw=400.0, lsb=1 / 16384, bits=16, b0=(0.02, 0.02, 0.02),
                   sf=0.01, xa=0.01, tc_b=1.0, tc_s=0.03, nl=0.5, fs_g=2.0, t_lsb=1 / 512),
}

RATES = (50.0, 100.0, 104.0, 125.0, 200.0, 208.0, 250.0, 400.0, 500.0, 1000.0)


def loguniform(rng, lo, hi):
    """A value log-uniform in [lo, hi] (magnitudes from barely visible to strong)."""
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def random_unit(rng, n=None):
    v = rng.normal(size=(3,) if n is None else (n, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def make_part(rng, name):
    """True linear calibration of one specimen of a part: M = (I + diag(sf)) + cross-axis
    (a full 3x3 matrix: scale errors, non-orthogonality and a small mounting rotation) and
    zero-g offsets b0, drawn from the datasheet tolerances (datasheet +- taken as 2 sigma)."""
    p = dict(PARTS[name])
    p["name"] = name
    m = np.eye(3) + np.diag(rng.normal(0.0, p["sf"], 3))
    off = rng.normal(0.0, p["xa"], (3, 3))
    np.fill_diagonal(off, 0.0)
    p["M"] = m + off
    p["b0_vec"] = rng.normal(0.0, 1.0, 3) * np.array(p["b0"])
    return p


def plan_directions(rng, n):
    """n specific-force directions (sensor frame) of the static poses: a quasi-uniform
    Fibonacci set, randomly rotated, each jittered by up to ~15 deg (so never face-aligned),
    at least 12 deg apart, then ordered as a hand would visit them (greedy nearest
    neighbour from a random start)."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = math.pi * (1 + 5 ** 0.5) * k
    r = np.sqrt(1 - z * z)
    pts = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    pts = pts @ q.T
    out = []
    for p in pts:
        for _ in range(50):
            c = p + rng.normal(0, 0.13, 3)
            c /= np.linalg.norm(c)
            if all(np.dot(c, o) < math.cos(math.radians(12)) for o in out):
                break
        out.append(c)
    out = np.array(out)
    order = [int(rng.integers(n))]
    left = set(range(n)) - set(order)
    while left:
        last = out[order[-1]]
        nxt = max(left, key=lambda j: float(np.dot(out[j], last)))
        order.append(nxt)
        left.remove(nxt)
    return out[order]


def slerp(a, b, s):
    """Unit vectors along the great circle from a to b at fractions s (array)."""
    om = math.acos(max(-1.0, min(1.0, float(np.dot(a, b)))))
    if om < 1e-6:
        return np.repeat(a[None, :], len(s), 0)
    if math.pi - om < 1e-3:  # antipodal: go through any perpendicular
        perp = np.cross(a, random_unit(np.random.default_rng(0)))
        perp /= np.linalg.norm(perp)
        mid = perp
        s2 = np.asarray(s)
        first = slerp(a, mid, np.clip(2 * s2, 0, 1))
        second = slerp(mid, b, np.clip(2 * s2 - 1, 0, 1))
        return np.where((s2 < 0.5)[:, None], first, second)
    s = np.asarray(s)[:, None]
    return (np.sin((1 - s) * om) * a + np.sin(s * om) * b) / math.sin(om)


def bandnoise(rng, n, fs, f_lo, f_hi, rms):
    """Gaussian noise with a flat spectrum between f_lo and f_hi Hz (FFT brick-wall), scaled
    to the given rms.  Returns (n,) array."""
    if n < 4:
        return np.zeros(n)
    w = np.fft.rfft(rng.normal(size=n))
    f = np.fft.rfftfreq(n, 1 / fs)
    w[(f < f_lo) | (f > min(f_hi, fs / 2))] = 0
    x = np.fft.irfft(w, n)
    sd = x.std()
    return x * (rms / sd) if sd > 0 else x


def min_jerk(tau):
    """Minimum-jerk position profile s(tau), tau in [0,1] (hand movements)."""
    return 10 * tau ** 3 - 15 * tau ** 4 + 6 * tau ** 5


def min_jerk_acc(tau):
    """Second derivative of min_jerk with respect to tau."""
    return 60 * tau - 180 * tau ** 2 + 120 * tau ** 3


class Session:
    """One calibration session: timing, poses, true specific force, sensor-side terms."""

    def __init__(self, rng, small=False, part=None, max_samples=250_000):
        self.rng = rng
        self.part = make_part(rng, part or str(rng.choice(list(PARTS))))
        if small:
            n = int(rng.integers(12, 17))
            fs = 100.0
            hold = rng.uniform(3.0, 8.0)
        else:
            n = int(rng.integers(12, 41))
            hold = loguniform(rng, 2.0, 30.0)
            rates = [r for r in RATES if r <= 2.5 * self.part["bw"]]
            fs = float(rng.choice(rates))
            # keep the log to a size a laptop logger would write in one session
            while n * (hold + 2.5) * fs > max_samples:
                if hold > 4.0:
                    # 0.999: a strict decrease (at the exact limit, rounding could loop forever)
                    hold = max(4.0, 0.999 * max_samples / (n * fs) - 2.5)
                else:
                    fs = max(r for r in RATES if r < fs) if fs > RATES[0] else fs
                    if fs == RATES[0]:
                        break
        self.fs, self.n_poses, self.hold_nominal = fs, n, hold
        self.u = plan_directions(rng, n)
        dt = 1 / fs
        holds = hold * rng.uniform(0.75, 1.3, n)  # floored at 2 s below
        trans = rng.uniform(1.2, 3.5, n - 1)
        lead = rng.uniform(0.0, 1.0)
        # sample index layout
        segs = []  # (kind, k, n_samples)
        if lead > 0:
            segs.append(("lead", 0, int(lead * fs)))
        for k in range(n):
            segs.append(("hold", k, max(int(holds[k] * fs), int(2.0 * fs))))
            if k < n - 1:
                segs.append(("move", k, int(trans[k] * fs)))
        N = sum(s[2] for s in segs)
        self.N = N
        self.t_true = np.arange(N) * dt
        self.f = np.zeros((N, 3))
        self.pose = np.full(N, -1, dtype=int)
        self.holds = []  # (start, end) sample indices, end exclusive
        i = 0
        for kind, k, m in segs:
            sl = slice(i, i + m)
            if kind == "lead":
                self.f[sl] = self.u[0]
            elif kind == "hold":
                self.f[sl] = self.u[k]
                self.pose[sl] = k
                self.holds.append((i, i + m))
            else:
                self._hand_turn(sl, m, self.u[k], self.u[k + 1])
            i += m
        self.bias = np.zeros((N, 3))
        self.scale = np.zeros((N, 3))
        self.noise = np.zeros((N, 3))
        self.nl = []
        self.temp_log = None
        self.duration = N * dt

    def _hand_turn(self, sl, m, a, b):
        """Hand rotation from pose a to pose b in m samples: the gravity direction follows a
        minimum-jerk great-circle path, the hand translates the device by 3-15 cm along a
        minimum-jerk path (linear acceleration D s''(tau)/T^2), plus physiological tremor
        (8-12 Hz, 5-30 mg rms) and slower hand jitter (1-4 Hz, 10-60 mg rms)."""
        rng, fs = self.rng, self.fs
        tau = np.linspace(0, 1, m, endpoint=False)
        dirs = slerp(a, b, min_jerk(tau))
        T = m / fs
        d = random_unit(rng) * rng.uniform(0.03, 0.15) / G0  # metres -> g*s^2
        lin = np.outer(min_jerk_acc(tau) / T ** 2, d)
        trem = np.stack([bandnoise(rng, m, fs, 8, 12, rng.uniform(0.005, 0.03)) for _ in range(3)], 1)
        jit = np.stack([bandnoise(rng, m, fs, 1, 4, rng.uniform(0.01, 0.06)) for _ in range(3)], 1)
        env = np.sin(np.pi * tau)[:, None]  # the hand's motion fades in and out
        self.f[sl] = dirs + lin + env * (trem + jit)

    # helpers for injectors -------------------------------------------------------
    def hold_mask(self):
        return self.pose >= 0

    def set_temperature(self, temp_c):
        """Logged temperature column: the sensor's temperature sensor reading (adds its own
        0.02 degC rms noise and quantises to the part's temperature LSB)."""
        t = temp_c + self.rng.normal(0, 0.02, self.N)
        q = self.part["t_lsb"]
        self.temp_log = np.round(t / q) * q


def render(s, unit, timestamp_jitter=True):
    """Sensor output as a logger writes it.  Returns (t, values (N x 3), header, fmt)."""
    p, rng = s.part, s.rng
    f = s.f
    sensed = (1 + s.scale) * f
    for g in s.nl:
        sensed = sensed + g(f)
    y = sensed @ p["M"].T + p["b0_vec"] + s.bias + s.noise
    sigma = p["nd"] * math.sqrt(min(s.fs / 2, p["bw"]))
    y = y + rng.normal(0, sigma, y.shape)
    lsb = p["lsb"]
    full = 2 ** (p["bits"] - 1)
    counts = np.clip(np.round(y / lsb), -full, full - 1).astype(np.int64)
    s.white_sigma_g = sigma
    # timestamps: logger clock with a small rate error and, for some loggers, jitter
    t = s.t_true * (1 + rng.normal(0, 50e-6)) + rng.uniform(0, 2.0)
    if timestamp_jitter:
        t = t + rng.normal(0, 0.03 / s.fs, s.N)
        t = np.maximum.accumulate(t)
    if unit == "counts":
        return t, counts, ("ax", "ay", "az"), "%d"
    if unit == "g":
        return t, counts * lsb, ("ax (g)", "ay (g)", "az (g)"), "%.7f"
    return t, counts * lsb * G0, ("ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"), "%.6f"


def write_csv(path, t, vals, header, fmt, temp=None):
    cols = [t[:, None], vals]
    names = ["t", *header]
    fmts = ["%.6f"] + [fmt] * 3
    if temp is not None:
        cols.append(temp[:, None])
        names.append("temp")
        fmts.append("%.3f")
    arr = np.hstack([c.astype(float) for c in cols])
    np.savetxt(path, arr, fmt=fmts, delimiter=",", header=",".join(names), comments="")
