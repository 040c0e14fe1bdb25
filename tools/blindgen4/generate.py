#!/usr/bin/env python3
"""Physics-based generator of accelerometer calibration-session logs with known injected effects.

    python3 generate.py --out DIR --per-family N --seed S

Writes DIR/<family>-<shape>-<index>.csv and DIR/manifest.json. Deterministic in (seed).
Python 3 + numpy only. See README.md for the simulated chain and the shapes.
"""

import argparse
import json
import os
import time

import numpy as np

G0 = 9.80665
Z = np.array([0.0, 0.0, 1.0])


# ----------------------------------------------------------------------------- helpers
def lu(rng, a, b):
    """log-uniform draw in [a, b]"""
    return float(np.exp(rng.uniform(np.log(a), np.log(b))))


def unit(rng, n=3):
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def jsonable(x):
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        return float("%.12g" % float(x))
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.bool_,)):
        return bool(x)
    return x


def qmul(a, b):
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def qconj(q):
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def q_from_rotvec(v):
    v = np.asarray(v, float)
    th = np.linalg.norm(v, axis=-1, keepdims=True)
    half = 0.5 * th
    k = np.where(th > 1e-12, np.sin(half) / np.maximum(th, 1e-300), 0.5)
    return np.concatenate([np.cos(half), v * k], axis=-1)


def qrot(q, v):
    """rotate vectors v by quaternions q (sensor -> world when q is the attitude)"""
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def qmat(q):
    return np.stack([qrot(q, e) for e in np.eye(3)], axis=-1)


def rand_quat(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def slerp(q0, q1, s):
    d = float(np.dot(q0, q1))
    if d < 0:
        q1 = -q1
        d = -d
    d = min(d, 1.0)
    th = np.arccos(d)
    s = s[:, None]
    if th < 1e-6:
        q = q0 * (1 - s) + q1 * s
    else:
        q = (np.sin((1 - s) * th) * q0 + np.sin(s * th) * q1) / np.sin(th)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def minjerk(x):
    x = np.clip(x, 0, 1)
    return x * x * x * (10 - 15 * x + 6 * x * x)


def lag1(t, x, tau, dt=0.5):
    """first-order lag (time constant tau, s) of the signal x(t); exact recursion on a coarse grid"""
    if tau <= 0:
        return x.copy()
    tg = np.arange(t[0], t[-1] + dt, dt)
    xg = np.interp(tg, t, x)
    yg = np.empty_like(xg)
    a = np.exp(-dt / tau)
    y = xg[0]
    for i in range(len(xg)):
        y = a * y + (1 - a) * xg[i]
        yg[i] = y
    return np.interp(t, tg, yg)


def shaped_noise(rng, n, fs, psd, ndim=3):
    """Gaussian noise of one-sided PSD psd(f) (units^2/Hz), via FFT shaping"""
    nf = n // 2 + 1
    f = np.fft.rfftfreq(n, 1.0 / fs)
    amp = np.sqrt(np.maximum(psd(np.maximum(f, f[1] if n > 1 else 1.0)), 0.0) * fs * n / 2.0)
    amp[0] = 0.0
    spec = (rng.normal(size=(nf, ndim)) + 1j * rng.normal(size=(nf, ndim))) / np.sqrt(2) * amp[:, None]
    return np.fft.irfft(spec, n=n, axis=0)


def nice_len(n):
    return int(np.ceil(n / 2048.0) * 2048)


def block_mean_std(x, t, holds):
    """std (over holds) of the per-hold means of x (N,k): the pose-mean level variation"""
    ms = []
    for (a, b, _) in holds:
        i0, i1 = np.searchsorted(t, [a, b])
        if i1 > i0:
            ms.append(x[i0:i1].mean(axis=0))
    ms = np.array(ms)
    return ms.std(axis=0)


# ----------------------------------------------------------------------------- part & session
PARTS = [  # (name, range options g, bits, noise density range ug/rtHz)
    ("ADXL345-like", [2, 4, 8, 16], 13, (150, 400)),
    ("LIS3DH-like", [2, 4, 8, 16], 12, (180, 300)),
    ("BMA456-like", [2, 4, 8, 16], 16, (100, 200)),
    ("ICM-42688-like", [2, 4, 8, 16], 16, (60, 120)),
    ("ADXL355-like", [2, 4, 8], 20, (25, 60)),
    ("LSM6DSO-like", [2, 4, 8, 16], 16, (70, 160)),
    ("MMA8451-like", [2, 4, 8], 14, (99, 250)),
    ("KX134-like", [8, 16], 16, (120, 300)),
]
ODRS = [50, 100, 104, 125, 200, 208, 250, 400, 416, 500, 800, 833, 1000]


def make_part(rng, coarse=False, low_range=False, odr_max=1000, odr_min=50):
    name, ranges, bits, ndr = PARTS[rng.integers(len(PARTS))]
    if coarse:
        name, ranges, bits, ndr = ("coarse-12bit", [8, 16], 12, (50, 120))
    rng_g = 2 if low_range else int(rng.choice(ranges))
    if name == "ADXL355-like":
        bits = 20
    nd = lu(rng, max(50, ndr[0]), max(50, ndr[1])) * 1e-6  # g/rtHz, the brief's 50-400 window
    nd = min(nd, 400e-6)
    odrs = [o for o in ODRS if odr_min <= o <= odr_max]
    odr = float(rng.choice(odrs))
    order = int(rng.choice([1, 2, 2, 3, 4]))
    fc = odr * rng.uniform(0.18, 0.45)
    lsb = 2.0 * rng_g / 2 ** bits
    # affine sensor errors
    bias = rng.uniform(-0.06, 0.06, 3)
    scale = rng.uniform(-0.03, 0.03, 3)
    cross = rng.uniform(-0.02, 0.02, (3, 3))
    A0 = np.eye(3) + np.diag(scale)
    off = ~np.eye(3, dtype=bool)
    A0[off] = cross[off]
    mount = q_from_rotvec(unit(rng) * np.radians(rng.uniform(0, 1.5)))
    M = qmat(mount)
    n = order
    enbw = fc * (np.pi / (2 * n)) / np.sin(np.pi / (2 * n))
    return dict(name=name, range_g=rng_g, bits=bits, lsb=lsb, nd=nd, odr=odr, fc=fc, order=order, enbw=enbw,
                bias=bias, A0=A0, M=M, sigma=nd * np.sqrt(enbw))


def cube_dirs():
    d = []
    for x in (-1, 0, 1):
        for y in (-1, 0, 1):
            for z in (-1, 0, 1):
                if (x, y, z) != (0, 0, 0):
                    d.append(np.array([x, y, z], float) / np.sqrt(x * x + y * y + z * z))
    return d


def quat_up_to(rng, g_sensor):
    """attitude q (sensor->world) such that world up [0,0,1] is seen along g_sensor, random heading"""
    g = g_sensor / np.linalg.norm(g_sensor)
    # rotation taking g (sensor) to Z (world)
    v = np.cross(g, Z)
    s = np.linalg.norm(v)
    c = np.dot(g, Z)
    if s < 1e-9:
        q = np.array([1.0, 0, 0, 0]) if c > 0 else np.array([0.0, 1.0, 0, 0])
    else:
        q = q_from_rotvec(v / s * np.arctan2(s, c))
    yaw = q_from_rotvec(Z * rng.uniform(-np.pi, np.pi))
    return qmul(yaw, q)


def make_session(rng, part, min_hold=2.0, prefer_long=False, hold_scale=None):
    odr = part["odr"]
    max_dur = 150000.0 / odr
    jig = rng.random() < 0.3
    n = int(rng.integers(12, 41))
    if prefer_long:
        hmed = lu(rng, 8, 30)
    else:
        hmed = lu(rng, max(2.5, min_hold), 30) if hold_scale is None else hold_scale
    hmed = max(hmed, min_hold * 1.2)
    target_rows = lu(rng, 20000, 120000) if not prefer_long else lu(rng, 60000, 150000)
    holds = np.clip(hmed * np.exp(rng.normal(0, 0.3, n)), max(2.0, min_hold), 30.0)
    moves = rng.uniform(1.0, 5.0, n)
    total = holds.sum() + moves[:-1].sum()
    target = min(target_rows / odr, max_dur * 0.98)
    if total > target:
        # shrink the holds, then drop poses
        f = max((target - moves[:-1].sum()) / holds.sum(), max(2.0, min_hold) / holds.min())
        holds = np.clip(holds * f, max(2.0, min_hold), 30.0)
        while holds.sum() + moves[:-1].sum() > target and n > 12:
            n -= 1
            holds, moves = holds[:n], moves[:n]
    if holds.sum() + moves[:-1].sum() > max_dur * 0.99:
        return None
    # attitudes
    if jig:
        dirs = cube_dirs()
        faces = [d for d in dirs if np.count_nonzero(d) == 1]
        gs = []
        for i in range(n):
            d = faces[i % 6] if (i < 6 or rng.random() < 0.5) else dirs[rng.integers(len(dirs))]
            gs.append(d)
        order = rng.permutation(n)
        gs = [gs[i] for i in order]
        quats = []
        for g in gs:
            q = quat_up_to(rng, g)
            q = qmul(q, q_from_rotvec(unit(rng) * np.radians(rng.uniform(0.2, 3.0))))
            quats.append(q / np.linalg.norm(q))
    else:
        quats = [rand_quat(rng) for _ in range(n)]
    # timeline
    segs = []
    t = 0.0
    for i in range(n):
        segs.append((t, t + holds[i], i))
        t += holds[i]
        if i < n - 1:
            t += moves[i]
    return dict(n=n, jig=jig, quats=np.array(quats), holds=segs, moves=moves[:n - 1], duration=t)


# ----------------------------------------------------------------------------- simulation container
class Sim:
    def __init__(self, rng, part, sess, fs_min=200.0):
        self.rng = rng
        self.part = part
        self.sess = sess
        odr = part["odr"]
        self.os = int(max(2, np.ceil(fs_min / odr)))
        self.fs = odr * self.os
        self.N = int(np.floor(sess["duration"] * self.fs)) + 1
        self.t = np.arange(self.N) / self.fs
        N = self.N
        # attitude + position along the session
        q = np.empty((N, 4))
        pos = np.zeros((N, 3))
        holds = sess["holds"]
        quats = sess["quats"]
        lever = unit(rng) * rng.uniform(0.02, 0.18)  # sensor offset from the rotation pivot, m
        centres = rng.uniform(-0.1, 0.1, (sess["n"], 3)) * np.array([1, 1, 0.3])
        self.pose_idx = np.full(N, -1)
        for k, (a, b, i) in enumerate(holds):
            i0, i1 = np.searchsorted(self.t, [a, b])
            q[i0:i1] = quats[i]
            pos[i0:i1] = centres[i]
            self.pose_idx[i0:i1] = i
            if k + 1 < len(holds):
                a2 = holds[k + 1][0]
                j1 = np.searchsorted(self.t, a2)
                T = a2 - b
                s = minjerk((self.t[i1:j1] - b) / T)
                qq = slerp(quats[i], quats[i + 1], s)
                # out-of-plane wobble of the hand during the move
                wob = q_from_rotvec(np.outer(np.sin(np.pi * s), unit(rng) * np.radians(rng.uniform(0, 8))))
                q[i1:j1] = qmul(wob, qq)
                lift = np.outer(np.sin(np.pi * s) ** 2, [0, 0, rng.uniform(0.0, 0.08)])
                pos[i1:j1] = centres[i] + np.outer(s, centres[i + 1] - centres[i]) + lift
        # the last hold ends with the session, and its slice leaves the session's last row out: that row holds
        # the last pose too (left unset, `np.empty` gave it whatever was in memory: a NaN there, spread by the
        # low-pass filter, made a whole log NaN on seed 115)
        last_row = np.searchsorted(self.t, holds[-1][1])
        q[last_row:] = quats[holds[-1][2]]
        pos[last_row:] = centres[holds[-1][2]]
        self.pose_idx[last_row:] = holds[-1][2]
        q[self.pose_idx == -1] /= np.linalg.norm(q[self.pose_idx == -1], axis=1, keepdims=True)
        self.q = q
        self.pos = pos + qrot(q, lever)
        self.rot_pert = None       # (N,3) small world-frame rotation vector (rad)
        self.acc_extra_w = None    # (N,3) extra world acceleration (g)
        self.f_extra_s = None      # (N,3) extra sensor-frame specific force (g)
        self.bias_t = np.zeros((N, 3))
        self.scale_t = np.zeros((N, 3))
        self.nonlin = None         # function f(N,3) -> extra (N,3), on the sensing axes
        self.colored = None        # (N,3) additive (g)
        self.post_add = None       # function(t_out) -> (M,3) added after the filter (g)
        self.temp_die = None       # (N,) die temperature
        self.want_temp = False

    def hold_windows(self):
        return [(a, b, i) for (a, b, i) in self.sess["holds"]]

    def add(self, name, arr):
        cur = getattr(self, name)
        setattr(self, name, arr if cur is None else cur + arr)

    def render(self):
        p = self.part
        dt = 1.0 / self.fs
        acc = np.gradient(np.gradient(self.pos, dt, axis=0), dt, axis=0) / G0
        q = self.q
        if self.rot_pert is not None:
            q = qmul(q_from_rotvec(self.rot_pert), q)
        aw = acc + Z
        if self.acc_extra_w is not None:
            aw = aw + self.acc_extra_w
        f = qrot(qconj(q), aw)
        self.f_true_s = f
        if self.f_extra_s is not None:
            f = f + self.f_extra_s
        f = f @ p["M"].T
        y = f
        if self.nonlin is not None:
            y = y + self.nonlin(f)
        y = y @ p["A0"].T
        y = y * (1.0 + self.scale_t) + p["bias"] + self.bias_t
        y = y + self.rng.normal(size=y.shape) * p["nd"] * np.sqrt(self.fs / 2.0)
        if self.colored is not None:
            y = y + self.colored
        # anti-alias low-pass (Butterworth magnitude, zero phase) at the internal rate, then decimate
        pad = int(max(256, 8 * self.fs / p["fc"]))
        yp = np.pad(y, ((pad, pad), (0, 0)), mode="edge")
        L = nice_len(len(yp))
        Y = np.fft.rfft(yp, n=L, axis=0)
        fr = np.fft.rfftfreq(L, dt)
        H = 1.0 / np.sqrt(1.0 + (fr / p["fc"]) ** (2 * p["order"]))
        yp = np.fft.irfft(Y * H[:, None], n=L, axis=0)[pad:pad + self.N]
        self.H = lambda f_: 1.0 / np.sqrt(1.0 + (f_ / p["fc"]) ** (2 * p["order"]))
        y = yp[::self.os]
        tout = self.t[::self.os]
        if self.post_add is not None:
            y = y + self.post_add(tout)
        half = 2 ** (p["bits"] - 1)
        counts = np.clip(np.round(y / p["lsb"]), -half, half - 1).astype(np.int64)
        return tout, counts


# ----------------------------------------------------------------------------- temperature helpers
def temp_profile(rng, t, kind):
    T0 = rng.uniform(17, 30)
    D = t[-1]
    if kind == "flat":
        return T0 + 0.05 * np.sin(2 * np.pi * t / max(D, 1) * rng.uniform(0.3, 1.0)), dict(T0=T0)
    if kind == "selfheat":
        dT = rng.uniform(2, 12)
        tau = rng.uniform(0.08, 0.5) * D
        return T0 + dT * (1 - np.exp(-t / tau)), dict(T0=T0, dT=dT, tau_s=tau)
    if kind == "ramp":
        dT = rng.choice([-1, 1]) * rng.uniform(10, 45)
        ta, tb = sorted(rng.uniform(0.05, 0.95, 2) * D)
        tb = max(tb, ta + 0.25 * D)
        ch = T0 + dT * np.clip((t - ta) / (tb - ta), 0, 1)
        tau_pkg = rng.uniform(20, 150)
        return lag1(t, ch, tau_pkg), dict(T0=T0, dT=dT, ramp_start_s=ta, ramp_end_s=tb, tau_package_s=tau_pkg)
    if kind == "cooling":
        dT = rng.uniform(5, 30)
        tau = rng.uniform(0.15, 0.6) * D
        return T0 + dT * np.exp(-t / tau), dict(T0=T0, dT=dT, tau_s=tau)
    if kind == "hvac":
        A = rng.uniform(1.0, 4.0)
        P = rng.uniform(0.3, 1.0) * D
        ph = rng.uniform(0, 2 * np.pi)
        return T0 + A * np.sin(2 * np.pi * t / P + ph), dict(T0=T0, amp=A, period_s=P)
    raise ValueError(kind)


def thermometer(rng, t_out, T_die_out):
    lsb = float(rng.choice([1 / 256, 0.0625, 0.125, 0.25, 0.5, 1.0]))
    tau = rng.uniform(0.5, 10)
    upd = float(rng.choice([1.0, 2.0, 5.0, 10.0, 25.0]))
    offs = rng.uniform(-2, 2)
    rd = lag1(t_out, T_die_out, tau, dt=0.1) + offs
    # sample and hold at the update rate
    ti = np.floor(t_out * upd) / upd
    rd = np.interp(ti, t_out, rd) + rng.normal(0, rng.uniform(0.005, 0.05), len(t_out))
    rd = np.round(rd / lsb) * lsb
    dec = {1 / 256: 8, 0.0625: 4, 0.125: 3, 0.25: 2, 0.5: 1, 1.0: 1}[lsb]
    return rd, dict(lsb_C=lsb, tau_s=tau, update_hz=upd, offset_C=offs, decimals=dec)


def lpf_gain(part, f):
    return 1.0 / np.sqrt(1.0 + (f / part["fc"]) ** (2 * part["order"]))


def smooth_hold_window(sim, sel=None, ramp=0.3):
    """1 inside the selected holds, 0 elsewhere, with minimum-jerk ramps of `ramp` s at the edges"""
    w = np.zeros(sim.N)
    t = sim.t
    for k, (a, b, i) in enumerate(sim.sess["holds"]):
        if sel is not None and not sel[k]:
            continue
        i0, i1 = np.searchsorted(t, [a, b])
        r = min(ramp, 0.25 * (b - a))
        tt = t[i0:i1]
        w[i0:i1] = np.minimum(minjerk((tt - a) / r), minjerk((b - tt) / r))
    return w


def normalize_effect(e, mag):
    """scale e (N,3, g) so that the max-over-axes peak-to-peak equals mag (g); returns factor"""
    pp = (e.max(axis=0) - e.min(axis=0)).max()
    return mag / pp if pp > 0 else 0.0


# ----------------------------------------------------------------------------- families
def floors(part, sess):
    H = np.median([b - a for (a, b, _) in sess["holds"]])
    s_pm = part["nd"] / np.sqrt(2 * H)
    q = part["lsb"] / np.sqrt(12) * np.exp(-2 * np.pi ** 2 * (part["sigma"] / part["lsb"]) ** 2)
    return float(np.sqrt(s_pm ** 2 + q ** 2)), float(part["sigma"])


def fam_clean(rng, shape):
    kw = {}
    if shape == "coarse-lsb":
        kw = dict(coarse=True)
    part = make_part(rng, **kw)
    sess = make_session(rng, part, prefer_long=(shape == "warmup-zero-tc"))
    return part, sess, dict(fs_min=200)


def effect_clean(sim, rng, shape, fl):
    params = {}
    if shape == "warmup-zero-tc":
        kind = str(rng.choice(["selfheat", "cooling", "ramp"]))
        sim.temp_die, tp = temp_profile(rng, sim.t, kind)
        sim.want_temp = True
        params = dict(profile=kind, **tp, bias_tc_mg_per_C=[0, 0, 0])
    elif shape == "coarse-lsb":
        params = dict(lsb_mg=sim.part["lsb"] * 1e3, sigma_mg=sim.part["sigma"] * 1e3)
    elif shape == "units-jitter":
        params = dict(note="physical units and timestamp jitter")
    return 0.0, "mg", params


def effect_drift(sim, rng, shape, fl):
    t = sim.t
    D = t[-1]
    mag = fl * lu(rng, 1.0, 50.0)
    params = {}
    if shape == "linear":
        d = rng.normal(size=3)
        e = np.outer(t / D, d)
        tgt = "bias"
    elif shape == "two-tau-settling":
        t1 = rng.uniform(20, 150)
        t2 = rng.uniform(200, 1500)
        d1, d2 = rng.normal(size=3), rng.normal(size=3) * rng.uniform(0.3, 1.5)
        e = np.outer(np.exp(-t / t1), d1) + np.outer(np.exp(-t / t2), d2)
        tgt = "bias"
        params = dict(tau1_s=t1, tau2_s=t2)
    elif shape == "sine-wander":
        k = int(rng.integers(2, 5))
        e = np.zeros((len(t), 3))
        per = []
        for _ in range(k):
            P = D * lu(rng, 0.4, 3.0)
            per.append(P)
            e += np.outer(np.sin(2 * np.pi * t / P + rng.uniform(0, 2 * np.pi)), rng.normal(size=3))
        tgt = "bias"
        params = dict(periods_s=per)
    elif shape == "rbf-wander":
        k = int(rng.integers(4, 9))
        cs = np.linspace(-0.1, 1.1, k) * D
        w = D / (k - 1) * rng.uniform(0.6, 1.2)
        e = np.zeros((len(t), 3))
        for c in cs:
            e += np.outer(np.exp(-0.5 * ((t - c) / w) ** 2), rng.normal(size=3))
        tgt = "bias"
        params = dict(knots=k, width_s=w)
    elif shape == "log-creep":
        tau = rng.uniform(10, 300)
        e = np.outer(np.log1p(t / tau), rng.normal(size=3))
        tgt = "bias"
        params = dict(tau_s=tau)
    elif shape == "scale-aging":
        tau = rng.uniform(30, 600)
        common = rng.normal() * np.ones(3) + rng.normal(0, 0.3, 3)
        e = np.outer(1 - np.exp(-t / tau), common) if rng.random() < 0.5 else np.outer(t / D, common)
        tgt = "scale"
        params = dict(tau_s=tau, per_axis_weights=common)
    else:
        raise ValueError(shape)
    k = normalize_effect(e, mag)
    e = e * k
    if tgt == "bias":
        sim.bias_t += e
    else:
        sim.scale_t += e  # relative scale change (equals g-change at 1 g)
    params.update(target=tgt, pp_per_axis_mg=(e.max(0) - e.min(0)) * 1e3)
    if rng.random() < 0.4:
        sim.temp_die, _ = temp_profile(rng, t, "flat")
        sim.want_temp = True
    return mag * 1e3, "mg (max-axis peak-to-peak offset change, or scale change x 1 g)", params


TEMP_SHAPES = {
    "selfheat-linear-bias": ("selfheat", "linear", False),
    "ramp-quadratic-bias": ("ramp", "quadratic", False),
    "cooling-scale-bias": ("cooling", "scale", False),
    "lagged-element": (None, "linear", True),
    "hvac-cycle-per-axis": ("hvac", "linear-mixed-sign", False),
}


def effect_temperature(sim, rng, shape, fl):
    t = sim.t
    kind, law, lagged = TEMP_SHAPES[shape]
    if kind is None:
        kind = str(rng.choice(["selfheat", "ramp", "cooling"]))
    Tdie, tp = temp_profile(rng, t, kind)
    sim.temp_die = Tdie
    sim.want_temp = True
    lag = rng.uniform(20, 300) if (lagged or rng.random() < 0.25) else 0.0
    Te = lag1(t, Tdie, lag) if lag > 0 else Tdie
    Tref = 25.0
    dTe = Te - Tref
    mag = fl * lu(rng, 1.0, 50.0)
    c1 = rng.normal(size=3)
    if law == "linear-mixed-sign":
        c1 = rng.normal(size=3) * rng.choice([-1, 1], 3)
    eb = np.outer(dTe, c1)
    es = np.zeros_like(eb)
    c2 = np.zeros(3)
    cs = np.zeros(3)
    if law == "quadratic":
        Tv = rng.uniform(Te.min(), Te.max())
        c2 = rng.normal(size=3)
        c1 = c1 * rng.uniform(0, 0.5)
        eb = np.outer(dTe, c1) * (Te.max() - Te.min()) * 0.1 + np.outer((Te - Tv) ** 2, c2)
        params_law = dict(vertex_C=Tv)
    else:
        params_law = {}
    if law == "scale":
        cs = rng.normal(size=3)
        es = np.outer(dTe, cs)
    k = normalize_effect(eb + es, mag)
    sim.bias_t += (eb - eb[0]) * k + eb[0] * k  # absolute law around 25 C
    sim.scale_t += es * k
    # report coefficients in physical units
    params = dict(profile=kind, **tp, element_lag_s=lag, law=law, **params_law)
    if law == "quadratic":
        params["bias_tc2_mg_per_C2"] = c2 * k * 1e3
        params["bias_tc_mg_per_C_part"] = c1 * k * 1e3 * (Te.max() - Te.min()) * 0.1
    else:
        params["bias_tc_mg_per_C"] = c1 * k * 1e3
    if law == "scale":
        params["scale_tc_ppm_per_C"] = cs * k * 1e6
    e = (eb + es) * k
    params["pp_per_axis_mg"] = (e.max(0) - e.min(0)) * 1e3
    params["die_T_range_C"] = [float(Tdie.min()), float(Tdie.max())]
    return mag * 1e3, "mg (max-axis peak-to-peak of the temperature-induced offset/scale x 1 g)", params


def effect_nonlin(sim, rng, shape, fl):
    mag = lu(rng, 0.2e-3, 8e-3)  # g deviation at 1 g (largest axis)
    k2 = np.zeros(3)
    k3 = np.zeros(3)
    k5 = 0.0
    if shape == "quadratic":
        k2 = rng.normal(size=3)
    elif shape == "cubic":
        k3 = rng.normal(size=3)
    elif shape == "mixed":
        k2 = rng.normal(size=3)
        k3 = rng.normal(size=3)
    elif shape == "single-axis":
        ax = rng.integers(3)
        k2[ax] = rng.normal()
        k3[ax] = rng.normal() * rng.uniform(0, 1)
        k2 += rng.normal(0, 0.05, 3)
    elif shape == "soft-compression":
        k5 = 1.0
        k3 = -np.abs(rng.normal(0, 0.3, 3))
    tot = np.abs(k2) + np.abs(k3) + k5
    s = mag / tot.max()
    k2, k3, k5 = k2 * s, k3 * s, k5 * s
    if shape == "soft-compression":
        FS = sim.part["range_g"]
        # output compresses as the input approaches full scale: -k5*a^5 style, pinned to mag at 1 g
        sim.nonlin = lambda f: k2 * f ** 2 + k3 * f ** 3 - k5 * f * np.abs(f) ** 4
        params = dict(k3_mg=k3 * 1e3, k5_mg=k5 * 1e3, full_scale_g=FS, compression_at_FS_mg=k5 * FS ** 5 * 1e3)
    else:
        sim.nonlin = lambda f: k2 * f ** 2 + k3 * f ** 3
        params = dict(k2_mg_per_g2=k2 * 1e3, k3_mg_per_g3=k3 * 1e3)
    return mag * 1e3, "mg (largest per-axis |k2|+|k3| deviation at 1 g)", params


def hold_time_since(sim):
    """time since the start of the current hold (inf during moves) and hold index array"""
    ts = np.full(sim.N, np.inf)
    hid = np.full(sim.N, -1)
    for k, (a, b, i) in enumerate(sim.sess["holds"]):
        i0, i1 = np.searchsorted(sim.t, [a, b])
        ts[i0:i1] = sim.t[i0:i1] - a
        hid[i0:i1] = k
    return ts, hid


def effect_settling(sim, rng, shape, fl, sig):
    ts, hid = hold_time_since(sim)
    nh = len(sim.sess["holds"])
    odr = sim.part["odr"]
    tau = sim.sess["settle_tau"]
    mag = sig / np.sqrt(tau * odr) * lu(rng, 1.0, 50.0)
    amps = mag * lu(rng, 0.5, 1.0) * np.exp(rng.normal(0, 0.3, nh))
    amps = np.minimum(amps, mag)
    amps[rng.integers(nh)] = mag
    a = amps[np.maximum(hid, 0)] * (hid >= 0)
    tsf = np.where(np.isfinite(ts), ts, 0.0)
    params = dict(tau_s=tau)
    if shape in ("support-creep", "creep-and-ring"):
        axes = np.array([unit(rng) * np.array([1, 1, 0]) for _ in range(nh)])
        axes /= np.linalg.norm(axes, axis=1, keepdims=True)
        rv = (a * np.exp(-tsf / tau))[:, None] * axes[np.maximum(hid, 0)]
        sim.add("rot_pert", rv)
        params["tilt_deg_max"] = np.degrees(mag)
    if shape in ("ringing", "creep-and-ring"):
        fr = rng.uniform(3, min(40, 0.4 * odr))
        dirs = np.array([unit(rng) for _ in range(nh)])
        ph = rng.uniform(0, 2 * np.pi, nh)
        env = np.exp(-tsf / tau) * np.sin(2 * np.pi * fr * tsf + ph[np.maximum(hid, 0)])
        sim.add("f_extra_s", (a * env)[:, None] * dirs[np.maximum(hid, 0)])
        params["ring_hz"] = fr
    if shape == "shock-offset-recovery":
        d = unit(rng)
        dirs = np.array([d * rng.choice([-1, 1]) * 0.3 + unit(rng) * 0.7 for _ in range(nh)])
        sim.bias_t += (a * np.exp(-tsf / tau))[:, None] * dirs[np.maximum(hid, 0)]
    if shape == "hand-thermal":
        # the hand warms the package during handling; offset from the thermal gradient decays after placement
        d = unit(rng)
        mv = np.concatenate([[2.0], sim.sess["moves"]])
        w = (mv / mv.max())[np.arange(nh)]
        tr = rng.uniform(0.1, 0.4) * tau
        shp = np.exp(-tsf / tau) - np.exp(-tsf / tr)
        shp /= max(shp.max(), 1e-12)
        sim.bias_t += (a * w[np.maximum(hid, 0)] * shp)[:, None] * d
        params["rise_s"] = tr
    return mag * 1e3, "mg (initial transient amplitude, largest hold; tilt in mrad for creep)", params


def effect_motion(sim, rng, shape, fl, sig):
    ts, hid = hold_time_since(sim)
    holds = sim.sess["holds"]
    nh = len(holds)
    t = sim.t
    fs = sim.fs
    params = {}
    inhold = (hid >= 0).astype(float)
    if shape == "taps":
        mag = sig * lu(rng, 3.0, 300.0)
        mag = min(mag, 1.5)
        f_extra = np.zeros((sim.N, 3))
        ntap = 0
        for (a, b, i) in holds:
            for _ in range(rng.poisson(rng.uniform(0.3, 2.0))):
                t0 = rng.uniform(a + 0.2, b - 0.2) if b - a > 0.5 else a + 0.5 * (b - a)
                fr = rng.uniform(15, min(150, 0.45 * fs))
                tau = rng.uniform(0.005, 0.06)
                i0 = np.searchsorted(t, t0)
                i1 = min(sim.N, i0 + int(8 * tau * fs) + 2)
                tt = t[i0:i1] - t0
                A = mag * lu(rng, 0.2, 1.0)
                f_extra[i0:i1] += np.outer(A * np.exp(-tt / tau) * np.sin(2 * np.pi * fr * tt), unit(rng))
                ntap += 1
        sim.add("acc_extra_w", f_extra)
        params = dict(taps=ntap)
        unitm = "mg (peak tap acceleration before the anti-alias filter)"
        return mag * 1e3, unitm, params
    if shape == "hand-held":
        sway = np.radians(lu(rng, 0.05, 1.0))
        fhi = rng.uniform(0.5, 2.5)
        rot = shaped_noise(rng, sim.N, fs, lambda f: 1.0 / (1 + (f / fhi) ** 4) / (1 + (0.05 / f) ** 2))
        rot *= sway / rot.std()
        ftr = rng.uniform(8, min(12, 0.45 * fs))
        trem_amp = sway * lu(rng, 0.02, 0.2)
        trem = shaped_noise(rng, sim.N, fs, lambda f: np.exp(-0.5 * ((f - ftr) / 0.8) ** 2))
        trem *= trem_amp / trem.std()
        disp = shaped_noise(rng, sim.N, fs, lambda f: 1.0 / (1 + (f / fhi) ** 4) / (1 + (0.1 / f) ** 2))
        disp *= lu(rng, 0.3, 3.0) * 1e-3 / disp.std()  # metres
        # only some holds are hand-held (the others rest on the table)
        sel = rng.random(nh) < rng.uniform(0.4, 1.0)
        sel[rng.integers(nh)] = True
        w = smooth_hold_window(sim, sel, ramp=rng.uniform(0.3, 1.0))
        sim.add("rot_pert", (rot + trem) * w[:, None])
        sim.pos = sim.pos + disp * w[:, None]
        params = dict(sway_deg_rms=np.degrees(sway), band_hz=fhi, tremor_hz=ftr,
                      tremor_deg_rms=np.degrees(trem_amp), handheld_holds=int(sel.sum()))
        return np.degrees(sway), "deg rms sway", params
    if shape == "nudge":
        ang = max(np.radians(0.02), fl * np.sqrt(2) * lu(rng, 1.0, 50.0))
        rv = np.zeros((sim.N, 3))
        nn = 0
        for k, (a, b, i) in enumerate(holds):
            if rng.random() < 0.5 and b - a > 2.0:
                t0 = rng.uniform(a + 0.3 * (b - a), a + 0.8 * (b - a))
                dur = rng.uniform(0.1, 0.5)
                i0, i1 = np.searchsorted(t, [a, b])
                s = minjerk((t[i0:i1] - t0) / dur)
                rv[i0:i1] += np.outer(s, unit(rng) * ang * lu(rng, 0.3, 1.0))
                nn += 1
                # the nudge also slides the part a little: keep the new attitude until the next move
        if nn == 0:
            a, b, i = holds[len(holds) // 2]
            i0, i1 = np.searchsorted(t, [a, b])
            rv[i0:i1] += np.outer(minjerk((t[i0:i1] - (a + b) / 2) / 0.3), unit(rng) * ang)
            nn = 1
        sim.add("rot_pert", rv)
        return np.degrees(ang), "deg (largest nudge)", dict(nudges=nn)
    if shape == "footsteps":
        mag = sig * lu(rng, 0.5, 20.0)
        acc = np.zeros(sim.N)
        nb = int(rng.integers(2, 6))
        fstep = rng.uniform(1.6, 2.3)
        frs = rng.uniform(6, min(25, 0.4 * fs))
        for _ in range(nb):
            tb = rng.uniform(0, t[-1])
            dur = rng.uniform(5, 20)
            for ts0 in np.arange(tb, tb + dur, 1.0 / fstep):
                i0 = np.searchsorted(t, ts0)
                i1 = min(sim.N, i0 + int(0.5 * fs))
                tt = t[i0:i1] - ts0
                env = np.exp(-0.5 * ((ts0 - tb - dur / 2) / (dur / 3)) ** 2)  # approach and leave
                acc[i0:i1] += mag * env * np.exp(-tt / 0.05) * np.sin(2 * np.pi * frs * tt)
        ew = np.zeros((sim.N, 3))
        ew[:, 2] = acc
        ew[:, 0] = 0.2 * acc
        sim.add("acc_extra_w", ew)
        return mag * 1e3, "mg (peak floor acceleration)", dict(step_hz=fstep, floor_mode_hz=frs, bursts=nb)
    if shape == "truck-fan-bursts":
        mag = sig * lu(rng, 0.3, 15.0)
        acc = np.zeros((sim.N, 3))
        nb = int(rng.integers(1, 5))
        info = []
        for _ in range(nb):
            tb = rng.uniform(0, t[-1])
            dur = rng.uniform(3, 25)
            kind = "truck" if rng.random() < 0.6 else "fan"
            env = np.exp(-0.5 * ((t - tb) / (dur / 4)) ** 2) if kind == "truck" else \
                ((t > tb) & (t < tb + dur)).astype(float)
            if kind == "truck":
                f0 = rng.uniform(2, 15)
                x = shaped_noise(rng, sim.N, fs, lambda f: np.exp(-0.5 * ((f - f0) / (0.3 * f0)) ** 2), 1)[:, 0]
                x /= x.std()
            else:
                f0 = rng.uniform(10, min(60, 0.45 * fs))
                x = np.sin(2 * np.pi * f0 * t + rng.uniform(0, 6.3)) * np.sqrt(2)
            acc += np.outer(x * env, unit(rng) * np.array([0.4, 0.4, 1.0])) * mag * lu(rng, 0.4, 1.0)
            info.append(dict(kind=kind, f_hz=f0, start_s=tb, dur_s=dur))
        sim.add("acc_extra_w", acc)
        return mag * 1e3, "mg (rms of the strongest burst)", dict(bursts=info)
    raise ValueError(shape)


def effect_colored(sim, rng, shape, fl):
    t = sim.t
    fs = sim.fs
    N = sim.N
    mag = fl * lu(rng, 1.0, 50.0)
    params = {}
    if shape == "flicker":
        x = shaped_noise(rng, N, fs, lambda f: np.minimum(1.0 / f, max(t[-1], 1.0)))
    elif shape == "gauss-markov":
        tau = lu(rng, 0.5, 100.0)
        x = shaped_noise(rng, N, fs, lambda f: 1.0 / (1 + (2 * np.pi * f * tau) ** 2))
        params = dict(tau_s=tau)
    elif shape == "random-walk":
        x = shaped_noise(rng, N, fs, lambda f: 1.0 / f ** 2)
    elif shape == "telegraph":
        x = np.zeros((N, 3))
        taus = []
        for ax in range(3):
            if rng.random() < 0.35 and ax != 2:
                continue
            t_hi, t_lo = lu(rng, 0.5, 30), lu(rng, 0.5, 30)
            taus.append([ax, t_hi, t_lo])
            tt, st = 0.0, rng.random() < 0.5
            while tt < t[-1]:
                d = rng.exponential(t_hi if st else t_lo)
                if st:
                    i0, i1 = np.searchsorted(t, [tt, tt + d])
                    x[i0:i1, ax] = 1.0
                tt += d
                st = not st
            x[:, ax] *= lu(rng, 0.3, 1.0)
        params = dict(axis_tau_hi_lo_s=taus)
    elif shape == "mix":
        tau = lu(rng, 0.5, 60.0)
        x = shaped_noise(rng, N, fs, lambda f: 1.0 / (1 + (2 * np.pi * f * tau) ** 2))
        x /= x.std()
        y = shaped_noise(rng, N, fs, lambda f: np.minimum(1.0 / f, max(t[-1], 1)))
        x = x + y / y.std() * rng.uniform(0.3, 1.5)
        params = dict(gm_tau_s=tau)
    else:
        raise ValueError(shape)
    rho = rng.uniform(0, 0.8) if rng.random() < 0.5 else 0.0
    if rho > 0:
        x = (1 - rho) * x + rho * x[:, [rng.integers(3)]]
    x = x - x.mean(axis=0)
    bm = block_mean_std(x, t, sim.sess["holds"]).max()
    x *= mag / max(bm, 1e-30)
    if shape in ("flicker", "mix"):
        # 1/f corner: where the flicker PSD meets the white noise density (largest axis)
        f_ = np.fft.rfftfreq(N, 1.0 / fs)
        P = np.abs(np.fft.rfft(x, axis=0)) ** 2 * 2 / (fs * N)
        band = (f_ > 0.05) & (f_ < 0.5)
        K = float((P[band] * f_[band, None]).mean(axis=0).max())
        params["corner_hz"] = K / sim.part["nd"] ** 2
    sim.add("colored", x)
    params.update(correlation=rho, hold_mean_std_mg=block_mean_std(x, t, sim.sess["holds"]) * 1e3)
    return mag * 1e3, "mg (std over holds of the per-hold mean of the coloured component, largest axis)", params


def effect_ooc(sim, rng, shape, fl, sig):
    t = sim.t
    holds = sim.sess["holds"]
    nh = len(holds)
    params = {}
    mag = fl * lu(rng, 1.0, 50.0)
    if shape == "flexed-board":
        # one (rarely two) poses clamped with board flex: package stress offset + slight misalignment
        ks = rng.choice(nh, size=1 if rng.random() < 0.7 else 2, replace=False)
        d = unit(rng)
        e = np.zeros((sim.N, 3))
        rv = np.zeros((sim.N, 3))
        for k in ks:
            a, b, _ = holds[k]
            i0, i1 = np.searchsorted(t, [a, b])
            e[i0:i1] = d * mag
            rv[i0:i1] = unit(rng) * mag * 0.5
        sim.bias_t += e
        sim.add("rot_pert", rv)
        params = dict(poses=ks, direction=d)
    elif shape == "motor-aliasing":
        odr = sim.part["odr"]
        k = int(rng.integers(1, 4))
        fm = k * odr + rng.choice([-1, 1]) * lu(rng, 0.005, 0.5)
        amp_out = sig * lu(rng, 0.3, 10.0)
        d = unit(rng)
        ph = rng.uniform(0, 2 * np.pi)
        # the vibration passes the weak anti-alias filter; the ADC samples it -> slow beat
        sim.post_add = lambda to: np.outer(amp_out * np.sin(2 * np.pi * fm * to + ph), d)
        mag = amp_out
        params = dict(motor_hz=fm, alias_hz=abs(fm - k * odr), direction=d,
                      amp_before_filter_mg=amp_out / max(lpf_gain(sim.part, fm), 1e-12) * 1e3)
    elif shape == "approach-hysteresis":
        # proof-mass stiction: the offset lags along the direction the gravity vector came from
        qs = sim.sess["quats"]
        gs = np.array([qrot(qconj(q), Z) for q in qs])
        e = np.zeros((sim.N, 3))
        for k, (a, b, i) in enumerate(holds):
            if k == 0:
                continue
            dv = gs[i] - gs[holds[k - 1][2]]
            dv /= max(np.linalg.norm(dv), 1e-9)
            i0 = np.searchsorted(t, a)
            i1 = np.searchsorted(t, holds[k + 1][0]) if k + 1 < nh else sim.N
            e[i0:i1] = -mag * dv
        sim.bias_t += e
    elif shape == "bilinear-cross":
        c = rng.normal(size=3)
        c *= mag / np.abs(c).max()
        sim.nonlin = lambda f: np.stack([c[0] * f[:, 1] * f[:, 2], c[1] * f[:, 0] * f[:, 2],
                                         c[2] * f[:, 0] * f[:, 1]], axis=1)
        params = dict(c_yz_xz_xy_mg=c * 1e3)
    elif shape == "offset-step":
        ts = rng.uniform(0.25, 0.75) * t[-1]
        d = unit(rng) * mag
        sim.bias_t += np.outer(t >= ts, d)
        params = dict(step_time_s=ts, step_mg=d * 1e3)
    elif shape == "mains-pickup":
        fm = float(rng.choice([50.0, 60.0])) * (1 + rng.normal(0, 2e-4))
        amp = sig * lu(rng, 0.2, 8.0)
        d = unit(rng)
        ph = rng.uniform(0, 2 * np.pi)
        h2 = rng.uniform(0, 0.5)
        sim.post_add = lambda to: np.outer(amp * (np.sin(2 * np.pi * fm * to + ph) +
                                                  h2 * np.sin(4 * np.pi * fm * to + 2 * ph)), d)
        mag = amp
        params = dict(mains_hz=fm, second_harmonic=h2, direction=d)
    elif shape == "loose-mount-rattle":
        # the board sits loose on one screw: in poses where gravity pulls it off its seat (g.e < thr) it tilts and rattles
        e_l = unit(rng)
        thr = rng.uniform(-0.3, 0.3)
        qs = sim.sess["quats"]
        rv = np.zeros((sim.N, 3))
        fx = np.zeros((sim.N, 3))
        loose = []
        for k, (a, b, i) in enumerate(holds):
            g = qrot(qconj(qs[i]), Z)
            if np.dot(g, e_l) < thr:
                loose.append(k)
                i0, i1 = np.searchsorted(t, [a, b])
                rv[i0:i1] = unit(rng) * mag
                for _ in range(rng.poisson(3 * (b - a))):
                    j = rng.integers(i0, max(i0 + 1, i1 - 20))
                    jj = min(i1, j + int(0.03 * sim.fs))
                    tt = t[j:jj] - t[j]
                    fx[j:jj] += np.outer(np.exp(-tt / 0.005) * np.sin(2 * np.pi * 90 * tt), e_l) * mag * 20
        sim.add("rot_pert", rv)
        sim.add("f_extra_s", fx)
        params = dict(loose_axis=e_l, threshold=thr, loose_holds=loose)
    else:
        raise ValueError(shape)
    return mag * 1e3, "mg", params


FAMILIES = {
    "clean": (["plain", "coarse-lsb", "warmup-zero-tc", "units-jitter"], "none"),
    "drift": (["linear", "two-tau-settling", "sine-wander", "rbf-wander", "log-creep", "scale-aging"], "drift"),
    "temperature": (list(TEMP_SHAPES), "temperature"),
    "scale-nonlinearity": (["quadratic", "cubic", "mixed", "single-axis", "soft-compression"], "scale-nonlinearity"),
    "settling": (["support-creep", "ringing", "shock-offset-recovery", "hand-thermal", "creep-and-ring"], "settling"),
    "motion": (["taps", "hand-held", "nudge", "footsteps", "truck-fan-bursts"], "motion"),
    "colored-noise": (["flicker", "gauss-markov", "random-walk", "telegraph", "mix"], "colored-noise"),
    "out-of-catalogue": (["flexed-board", "motor-aliasing", "approach-hysteresis", "bilinear-cross", "offset-step",
                          "mains-pickup", "loose-mount-rattle"], "honest"),
}


def build_one(seed, fam_idx, family, index, shape):
    rng = np.random.default_rng([seed, fam_idx, index, 4242])
    for attempt in range(20):
        coarse = family == "clean" and shape == "coarse-lsb"
        low = family == "scale-nonlinearity" and shape == "soft-compression"
        long_ = family in ("drift", "temperature") or (family == "colored-noise" and rng.random() < 0.5)
        odr_max = 250 if long_ else 1000
        if attempt >= 8:
            odr_max = 100
        part = make_part(rng, coarse=coarse, low_range=low, odr_max=odr_max)
        min_hold = 2.0
        settle_tau = None
        if family == "settling":
            settle_tau = lu(rng, 0.3, 4.0) if shape != "ringing" else lu(rng, 0.1, 1.5)
            min_hold = 4 * settle_tau + 1.5
        if family == "motion":
            min_hold = 4.0
        sess = make_session(rng, part, min_hold=min_hold, prefer_long=long_)
        if sess is not None and sess["n"] >= 12:
            break
    sess["settle_tau"] = settle_tau
    fs_min = 400.0 if family in ("motion", "settling", "out-of-catalogue") else 200.0
    sim = Sim(rng, part, sess, fs_min=fs_min)
    fl, sig = floors(part, sess)
    if family == "clean":
        mag, mu, params = effect_clean(sim, rng, shape, fl)
    elif family == "drift":
        mag, mu, params = effect_drift(sim, rng, shape, fl)
    elif family == "temperature":
        mag, mu, params = effect_temperature(sim, rng, shape, fl)
    elif family == "scale-nonlinearity":
        mag, mu, params = effect_nonlin(sim, rng, shape, fl)
    elif family == "settling":
        mag, mu, params = effect_settling(sim, rng, shape, fl, sig)
    elif family == "motion":
        mag, mu, params = effect_motion(sim, rng, shape, fl, sig)
    elif family == "colored-noise":
        mag, mu, params = effect_colored(sim, rng, shape, fl)
    else:
        mag, mu, params = effect_ooc(sim, rng, shape, fl, sig)
    if family == "clean" and shape != "warmup-zero-tc" and rng.random() < 0.25:
        sim.temp_die, _ = temp_profile(rng, sim.t, "flat")
        sim.want_temp = True
    tout, counts = sim.render()
    return rng, part, sess, sim, tout, counts, mag, mu, params, fl, sig


def write_log(path, rng, part, sim, tout, counts, units):
    odr = part["odr"]
    n = len(tout)
    ppm = rng.uniform(-150, 150)
    t0 = 0.0 if rng.random() < 0.6 else round(rng.uniform(1, 5000), 3)
    ts = t0 + np.arange(n) / (odr * (1 + ppm * 1e-6))
    jitter = 0.0
    if units == "g-jitter" or rng.random() < 0.2:
        jitter = rng.uniform(0.02, 0.3)
        ts = ts + rng.uniform(-jitter, jitter, n) / odr
        ts = np.maximum.accumulate(ts)
    cols = [ts]
    fmt = ["%.6f"]
    header = ["t"]
    lsb = part["lsb"]
    if units == "counts":
        cols += [counts[:, 0], counts[:, 1], counts[:, 2]]
        fmt += ["%d"] * 3
        header += ["ax", "ay", "az"]
    elif units.startswith("g"):
        cols += [counts[:, k] * lsb for k in range(3)]
        fmt += ["%.7f"] * 3
        header += ["ax (g)", "ay (g)", "az (g)"]
    else:
        cols += [counts[:, k] * lsb * G0 for k in range(3)]
        fmt += ["%.6f"] * 3
        header += ["ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"]
    tinfo = None
    if sim.want_temp and sim.temp_die is not None:
        Tout = sim.temp_die[::sim.os]
        rd, tinfo = thermometer(rng, tout, Tout)
        cols.append(rd)
        fmt.append("%%.%df" % tinfo["decimals"])
        if units == "counts":
            header.append("temp")
        else:
            header.append("temp")
    arr = np.column_stack(cols)
    np.savetxt(path, arr, fmt=fmt, delimiter=",", header=",".join(header), comments="")
    return dict(jitter_frac=jitter, clock_ppm=ppm, t0=t0, thermometer=tinfo, header=header)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--per-family", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--families", default=",".join(FAMILIES))
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    manifest = []
    t_start = time.time()
    for fi, family in enumerate(FAMILIES):
        if family not in a.families.split(","):
            continue
        shapes, expected = FAMILIES[family]
        srng = np.random.default_rng([a.seed, fi, 777])
        offset = int(srng.integers(len(shapes)))
        for idx in range(a.per_family):
            shape = shapes[(idx + offset) % len(shapes)]
            rng, part, sess, sim, tout, counts, mag, mu, params, fl, sig = build_one(a.seed, fi, family, idx, shape)
            u = rng.random()
            units = "counts" if u < 0.7 else ("g" if u < 0.85 else "ms2")
            if family == "clean" and shape == "units-jitter":
                units = "g-jitter" if rng.random() < 0.5 else "ms2"
            fname = f"{family}-{shape}-{idx}.csv"
            winfo = write_log(os.path.join(a.out, fname), rng, part, sim, tout, counts, units)
            gsens = np.array([qrot(qconj(q), Z) for q in sess["quats"]])
            A_tot = part["A0"] @ part["M"]
            entry = dict(
                file=fname, family=family, shape=shape, expected=expected, seed=a.seed, index=idx,
                magnitude=mag, magnitude_unit=mu, poses=sess["n"], duration_s=float(tout[-1]),
                rows=int(len(tout)), odr_hz=part["odr"], params=params,
                visibility_floor_mg=fl * 1e3, noise_sigma_mg=sig * 1e3,
                ratio_to_floor=(mag / (fl * 1e3)) if (mu.startswith("mg") and fl > 0) else None,
                part=dict(name=part["name"], range_g=part["range_g"], bits=part["bits"], lsb_mg=part["lsb"] * 1e3,
                          noise_ug_rtHz=part["nd"] * 1e6, lpf_hz=part["fc"], lpf_order=part["order"]),
                units="g" if units == "g-jitter" else units, jig=bool(sess["jig"]), timing=winfo,
                truth=dict(A=A_tot, bias_g=part["bias"], lsb_g=part["lsb"],
                           holds=[[a_, b_] for (a_, b_, _) in sess["holds"]],
                           pose_gravity_sensor=[gsens[i] for (_, _, i) in sess["holds"]]),
            )
            manifest.append(jsonable(entry))
    with open(os.path.join(a.out, "manifest.json"), "w") as fh:
        json.dump(manifest, fh, indent=1)
    print(f"wrote {len(manifest)} logs to {a.out} in {time.time() - t_start:.1f} s")


if __name__ == "__main__":
    main()
