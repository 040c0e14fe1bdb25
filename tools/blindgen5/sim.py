"""blindgen5 physics core: board trajectory, specific force, sensor part, rendering, CSV output.

Conventions
-----------
* World frame: z up.  Board attitude R maps sensor-frame vectors to the world frame.
* Specific force (what an accelerometer measures), in g:  f = R^T (a_lin / g0 + e_z),
  so a board lying still with +z up reads f = (0, 0, +1).
* a_lin is the second time derivative of the *sensor's* world position
  p_sensor = p_board + R r_lever  (board translation plus lever arm), computed by a
  central finite difference of the analytic trajectory (h = 1 ms).
"""
import numpy as np

G0 = 9.80665
EZ = np.array([0.0, 0.0, 1.0])
MAX_ROWS = 150000
ODRS = [50.0, 100.0, 104.0, 125.0, 200.0, 208.0, 250.0, 400.0, 416.0, 500.0, 800.0, 833.0, 1000.0]


# ----------------------------------------------------------------------------------------- maths
def loguni(rng, a, b):
    return float(np.exp(rng.uniform(np.log(a), np.log(b))))


def unit(rng, n=3):
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def smooth5(u):
    """Minimum-jerk smoothstep (C2), 0 -> 1 on [0, 1]."""
    u = np.clip(u, 0.0, 1.0)
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u))


def bump6(u):
    """C2 bump, 0 at both ends, 1 at u = 0.5."""
    u = np.clip(u, 0.0, 1.0)
    return 64.0 * (u * (1.0 - u)) ** 3


def onset_env(tau, t_decay, t_rise):
    """Smooth-onset decaying envelope (zero value/slope/curvature at tau = 0), peak ~ 1."""
    tau = np.maximum(tau, 0.0)
    e = np.exp(-tau / t_decay) * (1.0 - np.exp(-tau / t_rise)) ** 2
    return np.where(tau > 0, e, 0.0)


def qmul(a, b):
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def qconj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def qexp(v):
    v = np.asarray(v, float)
    ang = np.linalg.norm(v, axis=-1, keepdims=True)
    safe = np.where(ang > 1e-12, ang, 1.0)
    k = np.where(ang > 1e-12, np.sin(0.5 * ang) / safe, 0.5)
    return np.concatenate([np.cos(0.5 * ang), v * k], axis=-1)


def qlog(q):
    q = np.where(q[..., :1] < 0, -q, q)
    vn = np.linalg.norm(q[..., 1:], axis=-1)
    ang = 2.0 * np.arctan2(vn, np.clip(q[..., 0], -1, 1))
    k = np.where(vn > 1e-12, ang / np.where(vn > 1e-12, vn, 1.0), 2.0)
    return q[..., 1:] * k[..., None]


def q2m(q):
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - w * z)
    R[..., 0, 2] = 2 * (x * z + w * y)
    R[..., 1, 0] = 2 * (x * y + w * z)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - w * x)
    R[..., 2, 0] = 2 * (x * z - w * y)
    R[..., 2, 1] = 2 * (y * z + w * x)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quat_for_up(d, yaw):
    """Attitude (sensor->world) whose sensor-frame 'up' direction is d, then yawed about world z."""
    d = np.asarray(d, float)
    d = d / np.linalg.norm(d)
    ax = np.cross(d, EZ)
    s = np.linalg.norm(ax)
    c = float(np.dot(d, EZ))
    if s < 1e-9:
        q1 = np.array([1.0, 0, 0, 0]) if c > 0 else np.array([0.0, 1.0, 0, 0])
    else:
        q1 = qexp(ax / s * np.arctan2(s, c))
    return qmul(qexp(np.array([0.0, 0.0, yaw])), q1)


def lag1(x, dt, tau, y0=None):
    """First-order lag on a regular coarse grid (exact discretisation)."""
    y = np.empty_like(x)
    if tau <= 0:
        return x.copy()
    a = 1.0 - np.exp(-dt / tau)
    acc = x[0] if y0 is None else y0
    for i in range(len(x)):
        acc += a * (x[i] - acc)
        y[i] = acc
    return y


# ------------------------------------------------------------------------------------ orientations
FACES = [np.array(v, float) for v in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1])]
EDGES = [np.array(v, float) / np.sqrt(2) for v in
         ([1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0], [1, 0, 1], [1, 0, -1], [-1, 0, 1], [-1, 0, -1],
          [0, 1, 1], [0, 1, -1], [0, -1, 1], [0, -1, -1])]
CORNERS = [np.array(v, float) / np.sqrt(3) for v in
           ([1, 1, 1], [1, 1, -1], [1, -1, 1], [1, -1, -1], [-1, 1, 1], [-1, 1, -1], [-1, -1, 1], [-1, -1, -1])]


def pose_ups(rng, mode, n):
    """Sensor-frame 'up' directions of the poses."""
    if mode == 'jig':
        kind = rng.choice(['faces+edges', 'faces+edges+corners', 'faces+corners', 'faces x2+edges'])
        if kind == 'faces+edges':
            ups = FACES + EDGES
        elif kind == 'faces+edges+corners':
            ups = FACES + EDGES + CORNERS
        elif kind == 'faces+corners':
            ups = FACES + CORNERS
        else:
            ups = FACES + EDGES + FACES
        # jig misplacement / board not perfectly square in the jig: ~0.2-2 deg
        tilt = np.deg2rad(loguni(rng, 0.2, 2.0))
        out = []
        for d in ups:
            e = d + tilt * rng.normal(size=3)
            out.append(e / np.linalg.norm(e))
        return out, kind
    if mode == 'spread':
        # Fibonacci sphere, randomly rotated and jittered, random order
        k = np.arange(n) + 0.5
        z = 1 - 2 * k / n
        ph = np.pi * (1 + 5 ** 0.5) * k
        pts = np.stack([np.sqrt(1 - z * z) * np.cos(ph), np.sqrt(1 - z * z) * np.sin(ph), z], 1)
        Rr = q2m(qexp(unit(rng) * rng.uniform(0, np.pi)))
        pts = pts @ Rr.T + 0.15 * rng.normal(size=pts.shape)
        pts /= np.linalg.norm(pts, axis=1, keepdims=True)
        pts = pts[rng.permutation(n)]
        return list(pts), 'spread'
    pts = rng.normal(size=(n, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    return list(pts), 'uniform'


# ----------------------------------------------------------------------------------------- session
class Session:
    """Sequence of static holds joined by smooth hand/robot moves (rotation + lift + lateral shift)."""

    def __init__(self, rng, mode=None, n_poses=None, hold_range=None, move_range=(1.0, 5.0)):
        if mode is None:
            mode = rng.choice(['jig', 'uniform', 'spread'], p=[0.2, 0.35, 0.45])
        if n_poses is None:
            r = rng.uniform()
            n_poses = int(rng.integers(12, 17) if r < 0.55 else (rng.integers(17, 29) if r < 0.8 else rng.integers(29, 41)))
        ups, kind = pose_ups(rng, mode, n_poses)
        n = len(ups)
        if hold_range is None:
            hb = loguni(rng, 3.0, 25.0)
            hold_range = (max(2.0, hb * 0.75), min(30.0, hb * 1.3))
        holds = rng.uniform(hold_range[0], hold_range[1], n)
        mb = rng.uniform(move_range[0], move_range[1])
        moves = np.clip(mb * rng.uniform(0.7, 1.4, n - 1), move_range[0], move_range[1])
        self.mode, self.kind, self.n = mode, kind, n
        self.ups = np.array(ups)
        self.q = np.array([quat_for_up(d, rng.uniform(-np.pi, np.pi)) for d in ups])
        self.P = np.zeros((n, 3))
        self.P[:, :2] = rng.uniform(-0.08, 0.08, (n, 2))
        self.lift = rng.uniform(0.02, 0.15, max(n - 1, 1))
        self.lever = rng.uniform(-0.05, 0.05, 3)
        hs, he = np.zeros(n), np.zeros(n)
        t = 0.0
        for k in range(n):
            hs[k] = t
            t += holds[k]
            he[k] = t
            if k < n - 1:
                t += moves[k]
        self.hs, self.he, self.holds, self.moves = hs, he, holds, moves
        self.duration = t
        self.B = np.stack([hs, he], 1).ravel()
        self.w = qlog(qmul(qconj(self.q[:-1]), self.q[1:])) if n > 1 else np.zeros((0, 3))
        self.perts = []  # callables t -> (theta_world (N,3) rad, dp_world (N,3) m)

    # segment lookup -------------------------------------------------------------------------
    def seg(self, t):
        idx = np.clip(np.searchsorted(self.B, t, 'right') - 1, 0, 2 * self.n - 1)
        k = idx // 2
        mv = (idx % 2 == 1) & (k < self.n - 1)
        return k, mv

    def hold_index(self, t):
        k, mv = self.seg(t)
        return np.where(mv, -1, k)

    def last_landing(self, t):
        """Index of the last placement at or before t and the time since it."""
        k = np.clip(np.searchsorted(self.hs, t, 'right') - 1, 0, self.n - 1)
        return k, t - self.hs[k]

    def hold_window(self, t, k, ramp=0.4):
        """C2 window, 1 inside hold k, 0 outside, ramps of `ramp` s at both ends."""
        r = min(ramp, 0.25 * self.holds[k])
        return smooth5((t - self.hs[k]) / r) * smooth5((self.he[k] - t) / r)

    # trajectory ---------------------------------------------------------------------------
    def base(self, t):
        k, mv = self.seg(t)
        q = self.q[k].copy()
        p = self.P[k].copy()
        if mv.any():
            km = k[mv]
            u = (t[mv] - self.he[km]) / (self.hs[km + 1] - self.he[km])
            s = smooth5(u)
            q[mv] = qmul(self.q[km], qexp(s[:, None] * self.w[km]))
            p[mv] = self.P[km] + s[:, None] * (self.P[km + 1] - self.P[km])
            p[mv, 2] += self.lift[km] * bump6(u)
        return q, p

    def pose(self, t, perturbed=True):
        q, p = self.base(t)
        if perturbed and self.perts:
            th = np.zeros((len(t), 3))
            dp = np.zeros((len(t), 3))
            for fn in self.perts:
                a, b = fn(t)
                th += a
                dp += b
            q = qmul(qexp(th), q)
            p = p + dp
        R = q2m(q)
        return R, p + R @ self.lever

    def specific_force(self, t, perturbed=True, h=1e-3):
        R, p0 = self.pose(t, perturbed)
        _, pm = self.pose(t - h, perturbed)
        _, pp = self.pose(t + h, perturbed)
        a = (pp - 2.0 * p0 + pm) / (h * h) / G0
        return np.einsum('nji,nj->ni', R, a + EZ)


# -------------------------------------------------------------------------------------------- part
BITS_RANGES = [(12, 2), (12, 4), (12, 8), (12, 16), (14, 2), (14, 4), (14, 8), (14, 16), (16, 2), (16, 4),
               (16, 8), (16, 16), (18, 2), (18, 4), (18, 8), (20, 2), (20, 4), (20, 8)]


class Part:
    def __init__(self, rng, duration, fs=None, nd=None, bits=None, range_g=None, max_lsb_mg=1.0,
                 min_lsb_mg=0.0, fir=None, units=None, jitter=None, fs_max=None, fs_min=None):
        ok = [f for f in ODRS if f * duration <= MAX_ROWS and (fs_max is None or f <= fs_max)
              and (fs_min is None or f >= fs_min)]
        if not ok:
            ok = [f for f in ODRS if f * duration <= MAX_ROWS][:1] or [50.0]
        if fs is None:
            # favour the lower rates (log-uniform over the allowed list index)
            i = int(np.floor(len(ok) * rng.uniform() ** 1.4))
            fs = ok[min(i, len(ok) - 1)]
        self.fs = float(fs)
        self.nd = loguni(rng, 50.0, 400.0) if nd is None else float(nd)  # ug/sqrt(Hz)
        self.nd_axes = self.nd * rng.uniform(0.8, 1.25, 3)
        if bits is None:
            cands = [(b, r) for b, r in BITS_RANGES
                     if min_lsb_mg <= 1000.0 * r / 2 ** (b - 1) <= max_lsb_mg]
            bits, range_g = cands[rng.integers(len(cands))]
        self.bits, self.range_g = int(bits), float(range_g)
        self.lsb_per_g = 2 ** (self.bits - 1) / self.range_g
        self.A = np.eye(3) + np.diag(rng.uniform(-0.03, 0.03, 3))
        off = rng.uniform(-0.02, 0.02, (3, 3))
        np.fill_diagonal(off, 0.0)
        self.A += off
        self.b = rng.uniform(-0.06, 0.06, 3)
        if fir is None:
            fir = rng.choice(['none', 'boxcar', 'sinc'], p=[0.65, 0.15, 0.2])
        self.fir_kind = str(fir)
        self.taps = None
        self.fir_param = 0.0
        if self.fir_kind == 'boxcar':
            m = int(rng.integers(2, 9))
            self.taps = np.ones(m) / m
            self.fir_param = m
        elif self.fir_kind == 'sinc':
            fc = rng.uniform(0.06, 0.4)  # cutoff / fs
            L = int(rng.integers(8, 33)) * 2 + 1
            n = np.arange(L) - (L - 1) / 2
            h = 2 * fc * np.sinc(2 * fc * n) * np.hamming(L)
            self.taps = h / h.sum()
            self.fir_param = fc
        if units is None:
            units = rng.choice(['counts', 'g', 'mps2'], p=[0.6, 0.25, 0.15])
        self.units = str(units)
        self.jitter = bool(rng.uniform() < 0.1) if jitter is None else bool(jitter)
        self.t0 = 0.0 if rng.uniform() < 0.6 else float(np.round(rng.uniform(0.0, 5000.0), 3))
        self.clock_ppm = float(rng.normal(0, 30))
        self.jit_frac = rng.uniform(0.05, 0.4) if self.jitter else 0.0

    def info(self):
        return dict(fs=self.fs, noise_density_ug=round(self.nd, 3), bits=self.bits, range_g=self.range_g,
                    lsb_mg=1000.0 / self.lsb_per_g, fir=self.fir_kind, fir_param=float(self.fir_param),
                    units=self.units, jitter=self.jitter, t0=self.t0,
                    A=self.A.round(6).tolist(), bias_g=self.b.round(6).tolist())


def fir_causal(y, taps):
    L = len(taps)
    pad = np.concatenate([np.repeat(y[:1], L - 1, axis=0), y], 0)
    out = np.empty_like(y)
    for j in range(y.shape[1]):
        out[:, j] = np.convolve(pad[:, j], taps, mode='valid')
    return out


# ------------------------------------------------------------------------------------- temperature
class Thermometer:
    """How the temperature column is produced from a temperature history (deg C)."""

    def __init__(self, rng, lag=None):
        self.lag = loguni(rng, 1.0, 90.0) if lag is None else float(lag)
        self.offset = rng.normal(0, 0.7)
        self.noise = loguni(rng, 0.005, 0.15)
        self.quant = float(rng.choice([0.0, 0.01, 0.0625, 0.1, 0.25, 0.5, 1.0], p=[.15, .15, .25, .2, .1, .1, .05]))
        self.rate = float(rng.choice([0.0, 10.0, 4.0, 1.0, 0.5]))  # 0: every sample
        self.dec = 4 if self.quant == 0.0 else max(2, int(np.ceil(-np.log10(self.quant))) + 1)

    def column(self, rng, t, tc, Tc):
        """t: sample times; tc/Tc: coarse grid of the temperature the thermometer is exposed to."""
        Tth = lag1(Tc, tc[1] - tc[0], self.lag)
        if self.rate > 0:
            ts = np.floor(t * self.rate) / self.rate
        else:
            ts = t
        T = np.interp(ts, tc, Tth) + self.offset
        if self.rate > 0:
            key = np.floor(t * self.rate).astype(np.int64)
            key -= key[0]
            T = T + self.noise * rng.normal(size=key[-1] + 1)[key]
        else:
            T = T + self.noise * rng.normal(size=len(t))
        if self.quant > 0:
            T = np.round(T / self.quant) * self.quant
        return T

    def info(self):
        return dict(therm_lag_s=self.lag, therm_offset_C=self.offset, therm_noise_C=self.noise,
                    therm_quant_C=self.quant, therm_rate_hz=self.rate)


def coarse_grid(duration, dt=0.2):
    return np.arange(0.0, duration + 2 * dt, dt)


# ------------------------------------------------------------------------------------------- output
def write_csv(path, t_out, data, units, temp=None, temp_dec=4):
    cols = ['t']
    if units == 'counts':
        cols += ['ax', 'ay', 'az']
        fmts = ['%.6f', '%d', '%d', '%d']
    elif units == 'g':
        cols += ['ax (g)', 'ay (g)', 'az (g)']
        fmts = ['%.6f'] * 4
    else:
        cols += ['ax (m/s^2)', 'ay (m/s^2)', 'az (m/s^2)']
        fmts = ['%.6f'] * 4
    arr = [t_out[:, None], data]
    if temp is not None:
        cols.append('temp')
        fmts.append('%.' + str(temp_dec) + 'f')
        arr.append(temp[:, None])
    M = np.concatenate(arr, 1)
    with open(path, 'w') as fh:
        fh.write(','.join(cols) + '\n')
        np.savetxt(fh, M, fmt=','.join(fmts))
