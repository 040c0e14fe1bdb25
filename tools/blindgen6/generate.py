#!/usr/bin/env python3
"""blindgen6 - independent generator of synthetic MEMS triaxial-accelerometer
static multi-pose calibration logs, built from sensor physics only.

Usage:
    python3 generate.py --out DIR --per-family N --seed S [--families a,b]

See README.md for the physics of every shape.
"""
import argparse
import json
import math
import os
import sys
import time
import zlib

import numpy as np

G0 = 9.80665
MAX_ROWS = 150000
FAMILIES = ['clean', 'drift', 'temperature', 'scale-nonlinearity', 'settling',
            'motion', 'colored-noise', 'out-of-catalogue']
EXPECTED = {'clean': 'none', 'out-of-catalogue': 'honest'}
Z = np.array([0.0, 0.0, 1.0])


def logu(rng, a, b):
    return float(math.exp(rng.uniform(math.log(a), math.log(b))))


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def rand_unit(rng, n=None):
    if n is None:
        return unit(rng.normal(size=3))
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


# ----------------------------------------------------------------------------
# rotations
# ----------------------------------------------------------------------------
def skew(v):
    v = np.atleast_2d(v)
    S = np.zeros((v.shape[0], 3, 3))
    S[:, 0, 1] = -v[:, 2]
    S[:, 0, 2] = v[:, 1]
    S[:, 1, 0] = v[:, 2]
    S[:, 1, 2] = -v[:, 0]
    S[:, 2, 0] = -v[:, 1]
    S[:, 2, 1] = v[:, 0]
    return S


def rotvec_to_mat(v):
    """Rodrigues, vectorised: (N,3) -> (N,3,3); (3,) -> (3,3)."""
    single = np.ndim(v) == 1
    v = np.atleast_2d(np.asarray(v, float))
    th = np.linalg.norm(v, axis=1)
    small = th < 1e-7
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th ** 2 / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th ** 2 / 24.0, (1.0 - np.cos(ths)) / ths ** 2)
    V = skew(v)
    R = np.eye(3)[None] + a[:, None, None] * V + b[:, None, None] * (V @ V)
    return R[0] if single else R


def Rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def mat_to_quat(R):
    tr = np.trace(R)
    if tr > 0:
        S = math.sqrt(tr + 1.0) * 2
        q = [0.25 * S, (R[2, 1] - R[1, 2]) / S, (R[0, 2] - R[2, 0]) / S, (R[1, 0] - R[0, 1]) / S]
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        S = math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2]) * 2
        q = [(R[2, 1] - R[1, 2]) / S, 0.25 * S, (R[0, 1] + R[1, 0]) / S, (R[0, 2] + R[2, 0]) / S]
    elif R[1, 1] > R[2, 2]:
        S = math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2]) * 2
        q = [(R[0, 2] - R[2, 0]) / S, (R[0, 1] + R[1, 0]) / S, 0.25 * S, (R[1, 2] + R[2, 1]) / S]
    else:
        S = math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1]) * 2
        q = [(R[1, 0] - R[0, 1]) / S, (R[0, 2] + R[2, 0]) / S, (R[1, 2] + R[2, 1]) / S, 0.25 * S]
    q = np.array(q)
    return q / np.linalg.norm(q)


def quat_to_mat(q):
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    R = np.empty((q.shape[0], 3, 3))
    R[:, 0, 0] = 1 - 2 * (y * y + z * z)
    R[:, 0, 1] = 2 * (x * y - z * w)
    R[:, 0, 2] = 2 * (x * z + y * w)
    R[:, 1, 0] = 2 * (x * y + z * w)
    R[:, 1, 1] = 1 - 2 * (x * x + z * z)
    R[:, 1, 2] = 2 * (y * z - x * w)
    R[:, 2, 0] = 2 * (x * z - y * w)
    R[:, 2, 1] = 2 * (y * z + x * w)
    R[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def slerp(q0, q1, s):
    d = np.sum(q0 * q1, axis=1)
    th = np.arccos(np.clip(d, -1.0, 1.0))
    sn = np.sin(th)
    small = sn < 1e-6
    sns = np.where(small, 1.0, sn)
    w0 = np.where(small, 1.0 - s, np.sin((1.0 - s) * th) / sns)
    w1 = np.where(small, s, np.sin(s * th) / sns)
    q = w0[:, None] * q0 + w1[:, None] * q1
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def frame_from_up(u, yaw):
    """Body->world rotation C such that world 'up' seen in the body is u."""
    u = unit(u)
    a = np.array([1.0, 0, 0]) if abs(u[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = unit(a - a.dot(u) * u)
    e2 = np.cross(u, e1)
    CT = np.column_stack([e1, e2, u])
    return Rz(yaw) @ CT.T


def tilt(rng, u, sigma_deg):
    v = rng.normal(size=3) * math.radians(sigma_deg)
    return rotvec_to_mat(v) @ u


def ang(u, v):
    return math.degrees(math.acos(max(-1.0, min(1.0, float(np.dot(unit(u), unit(v)))))))


# ----------------------------------------------------------------------------
# sessions: rigs, pose sequences, trajectory
# ----------------------------------------------------------------------------
RIGS = ['box', 'jig', 'gimbal', 'phone', 'random']


def jig_dirs():
    d = []
    for x in (-1, 0, 1):
        for y in (-1, 0, 1):
            for z in (-1, 0, 1):
                if (x, y, z) != (0, 0, 0):
                    d.append(unit([x, y, z]))
    return d


def sequence(rng, cands, n, min_sep):
    """Cycle through candidate up-vectors, random order, no two consecutive too close."""
    out = []
    pool = []
    while len(out) < n:
        if not pool:
            pool = list(rng.permutation(len(cands)))
        ok = [i for i in pool if not out or ang(cands[i], cands[out[-1]]) >= min_sep]
        if not ok:
            pool = []
            ok = [i for i in range(len(cands)) if not out or ang(cands[i], cands[out[-1]]) >= min_sep]
        i = ok[rng.integers(len(ok))]
        out.append(i)
        if i in pool:
            pool.remove(i)
    return out


def covers(Cs):
    """Every body axis is pointed (roughly) up and down at least once."""
    U = np.array([C.T @ Z for C in Cs])
    if not (np.all(U.max(axis=0) > 0.85) and np.all(U.min(axis=0) < -0.85)):
        return False
    # the directions must determine a general ellipsoid (no ring-plus-poles designs)
    x, y, z = U.T
    M = np.column_stack([x * x, y * y, z * z, x * y, x * z, y * z, x, y, z, np.ones_like(x)])
    sv = np.linalg.svd(M, compute_uv=False)
    return bool(sv[-1] > 3e-2 * sv[0])


def make_orientations(rng, rig, n):
    """A session plan that spans the sphere (as any calibration procedure asks)."""
    for _ in range(80):
        Cs, style = make_orientations1(rng, rig, n)
        if covers(Cs):
            break
    return Cs, style


def make_orientations1(rng, rig, n):
    """Return list of body->world rotations, and the move style."""
    Cs = []
    if rig == 'box':
        faces = [unit(v) for v in np.vstack([np.eye(3), -np.eye(3)])]
        seq = sequence(rng, faces, n, 60)
        table = rng.normal(size=3) * math.radians(logu(rng, 0.05, 1.0))
        table[2] = 0
        Rt = rotvec_to_mat(table)
        err = logu(rng, 0.2, 2.0)
        for i in seq:
            u = tilt(rng, faces[i], err)
            yaw = rng.integers(4) * math.pi / 2 + rng.normal() * math.radians(5)
            Cs.append(Rt @ frame_from_up(u, yaw))
        style = 'hand'
    elif rig == 'jig':
        d = jig_dirs()
        k = int(rng.choice([14, 18, 26]))
        sub = [d[i] for i in sorted(rng.permutation(26)[:k])] if k < 26 else d
        if k == 14:
            sub = [v for v in d if np.sum(np.abs(v) > 0.1) in (1, 3)]
        seq = sequence(rng, sub, n, 30)
        err = logu(rng, 0.03, 0.4)
        yaw0 = rng.uniform(0, 2 * math.pi)
        for i in seq:
            Cs.append(frame_from_up(tilt(rng, sub[i], err), yaw0 + rng.normal() * 0.02))
        style = 'hand'
    elif rig == 'phone':
        ups = []
        while len(ups) < n:
            kind = rng.choice(['up', 'down', 'prop', 'edge'], p=[0.2, 0.15, 0.4, 0.25])
            if kind == 'up':
                u = tilt(rng, Z, 0.5)
            elif kind == 'down':
                u = tilt(rng, -Z, 0.5)
            elif kind == 'prop':
                a = math.radians(rng.uniform(10, 80))
                axis = [np.array([1.0, 0, 0]), np.array([0, 1.0, 0])][rng.integers(2)] * rng.choice([-1, 1])
                u = rotvec_to_mat(axis * a) @ (Z * rng.choice([1, 1, 1, -1]))
            else:
                e = np.eye(3)[rng.integers(2)] * rng.choice([-1, 1])
                lean = math.radians(rng.uniform(2, 12))
                u = rotvec_to_mat(rand_unit(rng) * lean) @ e
            if ups and ang(u, ups[-1]) < 20:
                continue
            ups.append(unit(u))
        for u in ups:
            Cs.append(frame_from_up(u, rng.uniform(0, 2 * math.pi)))
        style = 'hand'
    elif rig == 'random':
        ups = []
        while len(ups) < n:
            u = rand_unit(rng)
            if ups and ang(u, ups[-1]) < 30:
                continue
            ups.append(u)
        for u in ups:
            Cs.append(frame_from_up(u, rng.uniform(0, 2 * math.pi)))
        style = rng.choice(['robot', 'hand'])
    else:  # gimbal
        dphi = math.radians(float(rng.choice([30, 45, 60])))
        dpsi = math.radians(float(rng.choice([30, 45, 60])))
        Cm = rotvec_to_mat(rng.normal(size=3) * math.radians(logu(rng, 0.05, 1.5)))
        phis = np.arange(0, 2 * math.pi - 1e-9, dphi)
        psis = np.arange(0, 2 * math.pi - 1e-9, dpsi)
        grid = []
        for i, p in enumerate(phis):
            ps = psis if i % 2 == 0 else psis[::-1]
            for q in ps:
                grid.append(Rx(p) @ Ry(q) @ Cm)
        # drop raster neighbours that leave gravity nearly unchanged (inner axis vertical)
        uniq = [grid[0]]
        for C in grid[1:]:
            if ang(C.T @ Z, uniq[-1].T @ Z) >= 20:
                uniq.append(C)
        # a session covers the whole raster: n poses spread evenly along it (cycled if short)
        L = len(uniq)
        start = int(rng.integers(L))
        if n <= L:
            idx = np.round(np.linspace(0, L - 1, n)).astype(int)
        else:
            idx = np.arange(n)
        last = None
        for i in idx:
            k = (int(i) + start) % L
            while last is not None and ang(uniq[k].T @ Z, last) < 20:
                k = (k + 1) % L
            Cs.append(uniq[k])
            last = uniq[k].T @ Z
        style = 'motor'
    return Cs, style


class Session:
    pass


def build_session(rng, rig, n, hold_base, hints):
    Cs, style = make_orientations(rng, rig, n)
    S = Session()
    S.rig, S.style, S.n = rig, str(style), n
    if style == 'hand':
        S.lever = rng.normal(size=3) * logu(rng, 0.01, 0.08)
        ps = [np.array([rng.normal() * 0.04, rng.normal() * 0.04, 0.0]) for _ in range(n)]
    elif style == 'robot':
        S.lever = rand_unit(rng) * rng.uniform(0.1, 0.4)
        ps = [np.zeros(3) for _ in range(n)]
    else:
        S.lever = rng.normal(size=3) * logu(rng, 0.005, 0.06)
        ps = [np.zeros(3) for _ in range(n)]
    if hints.get('lever'):
        S.lever = rand_unit(rng) * hints['lever']
    qs = [mat_to_quat(C) for C in Cs]
    for i in range(1, n):
        if np.dot(qs[i], qs[i - 1]) < 0:
            qs[i] = -qs[i]
    holds = [hold_base * rng.uniform(0.75, 1.35) for _ in range(n)]
    holds[0] *= rng.uniform(1.0, 1.6)
    moves = []
    for i in range(n - 1):
        a = math.degrees(2 * math.acos(min(1.0, abs(float(np.dot(qs[i], qs[i + 1]))))))
        if style == 'motor':
            w = hints.get('motor_speed', rng.uniform(30, 120))
            moves.append(0.5 + a / w)
        elif style == 'robot':
            moves.append(rng.uniform(1.0, 2.0) + a / 90.0)
        else:
            moves.append(rng.uniform(1.2, 2.5) + a / 120.0)
    t0, t1, kind = [], [], []
    q0, q1, p0, p1, lift = [], [], [], [], []
    wig_a, wig_f, wig_p = [], [], []
    K = 3
    t = 0.0
    S.holds = []
    for i in range(n):
        t0.append(t); t1.append(t + holds[i]); kind.append(0)
        q0.append(qs[i]); q1.append(qs[i]); p0.append(ps[i]); p1.append(ps[i]); lift.append(0.0)
        wig_a.append(np.zeros((3, K))); wig_f.append(np.ones(K)); wig_p.append(np.zeros(K))
        S.holds.append((t, t + holds[i]))
        t += holds[i]
        if i < n - 1:
            d = moves[i]
            t0.append(t); t1.append(t + d); kind.append(1)
            q0.append(qs[i]); q1.append(qs[i + 1]); p0.append(ps[i]); p1.append(ps[i + 1])
            if style == 'hand':
                lift.append(rng.uniform(0.03, 0.2) * hints.get('violence', 1.0))
                wig_a.append(rng.normal(size=(3, K)) * logu(rng, 0.001, 0.008) * hints.get('violence', 1.0))
                wig_f.append(rng.uniform(0.8, 4.0, K))
            elif style == 'robot':
                lift.append(rng.uniform(0.0, 0.05))
                wig_a.append(np.zeros((3, K)))
                wig_f.append(np.ones(K))
            else:
                lift.append(0.0)
                wig_a.append(np.zeros((3, K)))
                wig_f.append(np.ones(K))
            wig_p.append(rng.uniform(0, 2 * math.pi, K))
            t += d
    S.T = t
    S.t0, S.t1, S.kind = np.array(t0), np.array(t1), np.array(kind)
    S.q0, S.q1 = np.array(q0), np.array(q1)
    S.p0, S.p1, S.lift = np.array(p0), np.array(p1), np.array(lift)
    S.wig_a, S.wig_f, S.wig_p = np.array(wig_a), np.array(wig_f), np.array(wig_p)
    S.Cs = np.array(Cs)
    S.hold_durs = holds
    return S


def eval_traj(S, t):
    j = np.clip(np.searchsorted(S.t1, t, side='right'), 0, len(S.t1) - 1)
    dur = S.t1[j] - S.t0[j]
    tau = np.clip((t - S.t0[j]) / dur, 0.0, 1.0)
    s = tau ** 3 * (10 - 15 * tau + 6 * tau ** 2)
    q = slerp(S.q0[j], S.q1[j], s)
    C = quat_to_mat(q)
    win = np.sin(math.pi * tau) ** 4
    p = S.p0[j] + (S.p1[j] - S.p0[j]) * s[:, None]
    p[:, 2] += S.lift[j] * win
    wig = np.einsum('nik,nk->ni', S.wig_a[j], np.sin(2 * math.pi * S.wig_f[j] * t[:, None] + S.wig_p[j]))
    p += wig * win[:, None]
    return C, p


def nominal_kinematics(S, t):
    """C(t) body->world and the non-gravitational acceleration of the sensor point (world, g)."""
    h = 2e-3
    C, p = eval_traj(S, t)
    P = p + np.einsum('nij,j->ni', C, S.lever)
    Cm, pm = eval_traj(S, t - h)
    Pm = pm + np.einsum('nij,j->ni', Cm, S.lever)
    Cp, pp = eval_traj(S, t + h)
    Pp = pp + np.einsum('nij,j->ni', Cp, S.lever)
    acc = (Pp - 2 * P + Pm) / h ** 2 / G0
    return C, acc


# ----------------------------------------------------------------------------
# part (the nominal sensor)
# ----------------------------------------------------------------------------
RATES = [25, 50, 100, 104, 125, 200, 208, 400, 416, 500, 800, 1000, 1600]
RATE_W = [0.6, 1.2, 1.5, 0.6, 0.5, 1.2, 0.5, 1.0, 0.4, 0.4, 0.5, 0.3, 0.4]
BITS = [10, 12, 13, 14, 16, 18, 20]


def draw_part(rng, D, hints):
    P = {}
    allowed = [(r, w) for r, w in zip(RATES, RATE_W) if r * D <= MAX_ROWS * 0.97]
    # at least ~100 samples in the shortest hold (a slow part is held longer)
    allowed = [(r, w) for r, w in allowed if r * hints.get('hold_min_s', 10) >= 100] or allowed[-1:]
    if hints.get('rate_min'):
        allowed = [(r, w) for r, w in allowed if r >= hints['rate_min']] or allowed
    if hints.get('rate_max'):
        allowed = [(r, w) for r, w in allowed if r <= hints['rate_max']] or allowed
    if not allowed:
        allowed = [(25, 1.0)]
    w = np.array([a[1] for a in allowed])
    P['rate'] = float(allowed[rng.choice(len(allowed), p=w / w.sum())][0])
    lsb_lo, lsb_hi = hints.get('lsb', (3.5e-6, 4.0e-3))
    rprior = {2: 0.4, 4: 0.3, 8: 0.2, 16: 0.1}
    ranges = [hints['range']] if hints.get('range') else [2, 4, 8, 16]
    pairs = [(r, b) for r in ranges for b in BITS if lsb_lo <= 2 * r / 2 ** b <= lsb_hi]
    if not pairs:
        pairs = [(ranges[0], 16)]
    w = np.array([rprior.get(int(r), 0.25) for r, b in pairs])
    r_, b_ = pairs[rng.choice(len(pairs), p=w / w.sum())]
    P['range_g'] = float(r_)
    P['bits'] = int(b_)
    P['lsb_g'] = 2 * P['range_g'] / 2 ** P['bits']
    nlo, nhi = hints.get('noise', (20, 500))
    P['noise_ug_rthz'] = logu(rng, nlo, nhi)
    fk = hints.get('filter') or str(rng.choice(['none', 'iir1', 'biquad', 'avg'], p=[0.4, 0.2, 0.25, 0.15]))
    fs = P['rate']
    # a filter that settles within ~15 % of the typical hold (the user chose a sane bandwidth)
    fc_min = min(fs / 4, max(1.0, 5.3 / hints.get('hold_s', 5.0)))
    if fk == 'iir1':
        P['filter'] = {'type': 'iir1', 'fc_hz': max(fc_min, fs / logu(rng, 4, 30))}
    elif fk == 'biquad':
        P['filter'] = {'type': 'biquad-butterworth', 'fc_hz': max(fc_min, fs / logu(rng, 4, hints.get('fc_div_max', 30)))}
    elif fk == 'avg':
        P['filter'] = {'type': 'moving-average', 'taps': int(rng.integers(2, 9))}
    else:
        P['filter'] = {'type': 'none'}
    P['units'] = hints.get('units') or str(rng.choice(['counts', 'g', 'mps2', 'mg'], p=[0.35, 0.3, 0.2, 0.15]))
    A = np.eye(3)
    A[np.diag_indices(3)] += np.clip(rng.normal(size=3) * 0.015, -0.045, 0.045)
    off = ~np.eye(3, dtype=bool)
    A[off] += np.clip(rng.normal(size=6) * 0.008, -0.03, 0.03)
    P['A'] = A
    b = rng.uniform(-0.04, 0.04, 3)
    b[2] *= rng.uniform(1.0, 2.0)
    P['b'] = b
    tm = hints.get('timing') or str(rng.choice(['counter', 'host', 'fifo'], p=[0.5, 0.35, 0.15]))
    P['timing'] = tm
    P['clock_ppm'] = float(rng.normal() * hints.get('clock_sigma_ppm', 400))
    P['jitter_s'] = float(logu(rng, 1e-5, 0.12 / fs)) if tm == 'host' else 0.0
    P['fifo_batch'] = int(rng.integers(4, 33)) if tm == 'fifo' else 0
    P['drops'] = int(hints.get('drops', rng.choice([0, 0, 0, 1, 2])))
    P['t_start'] = float(rng.choice([0.0, round(rng.uniform(0, 5000), 3)]))
    return P


def filter_kernel(P):
    f = P['filter']
    fs = P['rate']
    if f['type'] == 'iir1':
        a = 1 - math.exp(-2 * math.pi * f['fc_hz'] / fs)
        L = int(min(20000, max(8, math.ceil(math.log(1e-9) / math.log(1 - a)))))
        return a * (1 - a) ** np.arange(L)
    if f['type'] == 'biquad-butterworth':
        K = math.tan(math.pi * f['fc_hz'] / fs)
        q = 1 / math.sqrt(2)
        norm = 1 / (1 + K / q + K * K)
        b0 = K * K * norm
        b1, b2 = 2 * b0, b0
        a1 = 2 * (K * K - 1) * norm
        a2 = (1 - K / q + K * K) * norm
        L = 4000
        h = np.zeros(L)
        x1 = x2 = y1 = y2 = 0.0
        for n in range(L):
            x = 1.0 if n == 0 else 0.0
            y = b0 * x + b1 * x1 + b2 * x2 - a1 * y1 - a2 * y2
            h[n] = y
            x2, x1 = x1, x
            y2, y1 = y1, y
            if n > 50 and abs(y) < 1e-12 and abs(y2) < 1e-12:
                return h[:n + 1]
        return h
    if f['type'] == 'moving-average':
        k = f['taps']
        return np.ones(k) / k
    return None


def apply_filter(x, h):
    if h is None or len(h) == 1:
        return x
    L = len(h)
    N = x.shape[0]
    xp = np.vstack([np.repeat(x[:1], L, axis=0), x])
    n = 1 << int(math.ceil(math.log2(xp.shape[0] + L)))
    Y = np.fft.irfft(np.fft.rfft(xp, n, axis=0) * np.fft.rfft(h, n)[:, None], n, axis=0)
    return Y[L:L + N]


# ----------------------------------------------------------------------------
# signal helpers
# ----------------------------------------------------------------------------
def colored(rng, N, fs, kind, **kw):
    """Unit-ish zero-mean colored process of length N (one column)."""
    if kind == 'rw':
        return np.cumsum(rng.normal(size=N)) / math.sqrt(fs)
    M = 1 << int(math.ceil(math.log2(2 * N)))
    f = np.fft.rfftfreq(M, 1 / fs)
    f[0] = f[1]
    if kind == 'flicker':
        amp = f ** (-kw.get('alpha', 1.0) / 2)
    elif kind == 'gm':
        tau = kw['tau']
        amp = 1 / np.sqrt(1 + (2 * math.pi * f * tau) ** 2)
    else:
        raise ValueError(kind)
    X = (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)) * amp
    X[0] = 0
    x = np.fft.irfft(X, M)[:N]
    return x / (np.std(x) + 1e-30)


def sines(rng, t, k, fmin, fmax, amp):
    """Sum of k sinusoids per axis: returns x, x', x'' (N,3)."""
    f = np.exp(rng.uniform(math.log(fmin), math.log(fmax), (3, k)))
    a = amp * rng.normal(size=(3, k)) / math.sqrt(k)
    ph = rng.uniform(0, 2 * math.pi, (3, k))
    w = 2 * math.pi * f
    arg = t[:, None, None] * w[None] + ph[None]
    x = np.sum(a * np.sin(arg), axis=2)
    xd = np.sum(a * w * np.cos(arg), axis=2)
    xdd = -np.sum(a * w * w * np.sin(arg), axis=2)
    return x, xd, xdd


def lag1(t, x, tau):
    """First-order thermal lag of x(t) with time constant tau (exact for piecewise-linear input)."""
    if tau <= 0:
        return x.copy()
    dt = max(0.02, min(tau / 10.0, 0.5))
    tg = np.arange(t[0], t[-1] + dt, dt)
    xg = np.interp(tg, t, x)
    yg = np.empty_like(xg)
    a = math.exp(-dt / tau)
    y = xg[0]
    for i in range(len(xg)):
        y = a * y + (1 - a) * xg[i]
        yg[i] = y
    return np.interp(t, tg, yg)


def damped(s, A, a, w):
    """A e^{-a s} sin(w s) and its first two derivatives for s >= 0 (0 before)."""
    e = np.where(s >= 0, np.exp(-a * np.clip(s, 0, None)), 0.0)
    sn, cs = np.sin(w * s), np.cos(w * s)
    x = A * e * sn
    xd = A * e * (w * cs - a * sn)
    xdd = A * e * ((a * a - w * w) * sn - 2 * a * w * cs)
    return x, xd, xdd


# ----------------------------------------------------------------------------
# the effect container
# ----------------------------------------------------------------------------
class Effect(dict):
    """keys: theta, dtheta, ddtheta (N,3 rad, body), r_s (3, m), acc_w (N,3 g world),
    bias (N,3 g), scale (N,3 fractional), nl (callable u->du), post (callable(f,u)->du),
    gl (local gravity factor), temp (N,) recorded temperature column, codes (callable)."""


def sensor_u(ctx, E, noise=None):
    """Pre-filter, pre-ADC sensor output in g (N,3)."""
    fw = ctx.acc_nom.copy()
    gl = E.get('gl', 1.0) if E else 1.0
    fw[:, 2] += gl
    if E is not None and E.get('acc_w') is not None:
        fw = fw + E['acc_w']
    f = np.einsum('nji,nj->ni', ctx.C, fw)
    if E is not None and E.get('theta') is not None:
        R = rotvec_to_mat(E['theta'])
        f = np.einsum('nji,nj->ni', R, f)
        r = E['r_s']
        td, tdd = E['dtheta'], E['ddtheta']
        f = f + (np.cross(tdd, r) + np.cross(td, np.cross(td, r))) / G0
    A = ctx.P['A']
    u = f @ A.T
    if E is not None:
        if E.get('scale') is not None:
            u = u + (f * E['scale']) @ A.T
        if E.get('nl') is not None:
            u = u + E['nl'](u)
        if E.get('post') is not None:
            u = u + E['post'](f, u)
        if E.get('bias') is not None:
            u = u + E['bias']
    u = u + ctx.P['b']
    if noise is not None:
        u = u + noise
    return u, f


# ----------------------------------------------------------------------------
# shapes.  Each shape: fn(ctx, rng, gain) -> (Effect, params).  The effect must be
# linear (or nearly) in gain; gain is set so that the peak effect over the hold
# samples equals the drawn magnitude.
# ----------------------------------------------------------------------------
def hold_mean_zero(ctx, x):
    return x - x[ctx.hold_mask].mean(axis=0)


def rand_dir(rng, weights=None):
    v = rng.normal(size=3)
    if weights is not None:
        v = v * np.asarray(weights)
    return unit(v)


# ---- clean -----------------------------------------------------------------
def clean_none(ctx, rng, gain):
    return Effect(), {}


def clean_tempcomp(ctx, rng, gain):
    T, p = temp_profile(ctx, rng, kind=str(rng.choice(['selfheat', 'ramp', 'handheat'])))
    E = Effect(temp=thermometer(ctx, rng, T, p))
    p['note'] = 'temperature varies but the part is fully temperature-compensated (no coupling)'
    return E, p


CLEAN = {
    'nominal': (clean_none, {}),
    'coarse-quant': (clean_none, {'lsb': (4e-3, 1.6e-2), 'noise': (20, 80), 'rate_max': 200}),
    'heavy-filter': (clean_none, {'filter': 'biquad', 'fc_div_max': 60, 'rate_min': 200, 'timing': 'fifo'}),
    'timing-mess': (clean_none, {'timing': 'host', 'clock_sigma_ppm': 12000, 'drops': 4}),
    'long-rich': (clean_none, {'poses': (40, 60), 'noise': (20, 60), 'lsb': (3.5e-6, 1.3e-4), 'hold': (6, 15)}),
    'short-noisy': (clean_none, {'poses': (12, 13), 'noise': (250, 500), 'hold': (2.2, 3.2)}),
    'temp-compensated': (clean_tempcomp, {}),
    'violent-moves': (clean_none, {'range': 2.0, 'rig': 'box', 'violence': 3.0, 'lever': 0.12}),
}


# ---- drift ----------------------------------------------------------------
def drift_bias_linear(ctx, rng, gain):
    v = rand_dir(rng, [1, 1, 1.5])
    x = ctx.t / ctx.T
    return Effect(bias=hold_mean_zero(ctx, gain * np.outer(x, v))), {'direction': v.tolist(), 'law': 'linear'}


def drift_bias_warmup(ctx, rng, gain):
    v = rand_dir(rng, [1, 1, 2])
    tau = ctx.T * rng.uniform(0.1, 0.6)
    x = 1 - np.exp(-ctx.t / tau)
    return Effect(bias=hold_mean_zero(ctx, gain * np.outer(x, v))), {'direction': v.tolist(), 'tau_s': tau}


def drift_scale_linear(ctx, rng, gain):
    w = rng.normal(size=3)
    w /= np.max(np.abs(w))
    x = ctx.t / ctx.T
    return Effect(scale=gain * np.outer(x, w)), {'scale_weights': w.tolist(), 'law': 'linear'}


def drift_bias_cyclic(ctx, rng, gain):
    v = rand_dir(rng)
    per = ctx.T * rng.uniform(0.3, 1.5)
    ph = rng.uniform(0, 2 * math.pi)
    x = np.sin(2 * math.pi * ctx.t / per + ph)
    return Effect(bias=hold_mean_zero(ctx, gain * np.outer(x, v))), {'direction': v.tolist(), 'period_s': per}


def drift_bias_scale_quad(ctx, rng, gain):
    v = rand_dir(rng)
    w = rng.normal(size=3) * rng.uniform(0.3, 1.5)
    x = ctx.t / ctx.T
    bias = hold_mean_zero(ctx, gain * np.outer(x ** 2 * rng.choice([-1, 1]), v))
    return Effect(bias=bias, scale=gain * np.outer(x, w)), {'direction': v.tolist(), 'scale_weights': w.tolist()}


def drift_axis_creep(ctx, rng, gain):
    ax = int(rng.choice([0, 1, 2], p=[0.2, 0.2, 0.6]))
    tau = rng.uniform(2, 60)
    x = np.log1p(ctx.t / tau) * rng.choice([-1, 1])
    b = np.zeros((len(ctx.t), 3))
    b[:, ax] = x
    return Effect(bias=hold_mean_zero(ctx, gain * b)), {'axis': ax, 'tau_s': tau, 'law': 'logarithmic creep'}


DRIFT = {
    'bias-linear': (drift_bias_linear, {'flat_temp': 0.4}),
    'bias-warmup': (drift_bias_warmup, {'flat_temp': 0.3}),
    'scale-linear': (drift_scale_linear, {'flat_temp': 0.4}),
    'bias-cyclic': (drift_bias_cyclic, {'flat_temp': 0.3}),
    'bias-scale-quadratic': (drift_bias_scale_quad, {'flat_temp': 0.4}),
    'axis-log-creep': (drift_axis_creep, {'flat_temp': 1.0}),
}


# ---- temperature -------------------------------------------------------------
def temp_profile(ctx, rng, kind):
    t, T = ctx.t, ctx.T
    amb = rng.uniform(18, 30)
    p = {'profile': kind, 'ambient_c': amb}
    if kind == 'selfheat':
        dT = rng.uniform(3, 15)
        tau = T * rng.uniform(0.12, 0.5)
        die = amb + dT * (1 - np.exp(-t / tau))
        p.update(rise_c=dT, tau_s=tau)
    elif kind == 'ramp':
        rate = rng.uniform(0.01, 0.1) * rng.choice([-1, 1, 1])
        rate = math.copysign(min(max(abs(rate), 3.0 / T), 25.0 / T), rate)
        taud = rng.uniform(5, 60)
        die = lag1(t, amb + rate * t, taud)
        p.update(rate_c_per_s=rate, die_lag_s=taud)
    elif kind == 'handheat':
        tau = rng.uniform(30, 200)
        pulse = rng.uniform(0.4, 2.0)
        src = np.zeros_like(t)
        for (a, b) in ctx.moves:
            src += pulse / max(b - a, 0.1) * ((t >= a) & (t < b))
        # heat input integrated then leaking with tau: dT/dt = src - (T)/tau
        # dT/dt = src - (T - amb)/tau  <=>  first-order lag of src*tau
        die = amb + lag1(t, src * tau, tau)
        lim = rng.uniform(2.0, 8.0)  # a hand warms a small board by a few degC at most
        if die.max() - amb > lim:
            die = amb + (die - amb) * lim / (die.max() - amb)
        p.update(pulse_c=pulse, tau_s=tau)
    elif kind == 'hvac':
        per = min(rng.uniform(300, 1500), rng.uniform(0.4, 1.0) * T)
        a = rng.uniform(1.5, 4)
        die = lag1(t, amb + a * np.sign(np.sin(2 * math.pi * t / per + rng.uniform(0, 6.28))), rng.uniform(30, 120))
        p.update(period_s=per, swing_c=a)
    elif kind == 'chamber':
        nst = int(rng.integers(2, 5))
        lv = amb + np.cumsum(rng.uniform(5, 20, nst) * rng.choice([-1, 1], nst))
        edges = np.sort(rng.uniform(0.1, 0.8, nst - 1)) * T
        sp = np.full_like(t, amb)
        for i, e in enumerate(edges):
            sp[t >= e] = lv[i]
        die = lag1(t, sp, rng.uniform(20, 100))
        p.update(setpoints_c=lv.tolist())
    else:
        raise ValueError(kind)
    span = float(die.max() - die.min())
    if span < 1.5:  # make sure temperature really varies
        die = amb + (die - die.min()) * (1.5 / max(span, 1e-9)) if span > 1e-6 else amb + 1.5 * t / T
    p['die_span_c'] = float(die.max() - die.min())
    return die, p


def thermometer(ctx, rng, die, p):
    onchip = rng.random() < 0.6
    lag = rng.uniform(0.5, 5) if onchip else rng.uniform(10, 120)
    off = rng.normal() * (0.5 if onchip else 2.0)
    q = float(rng.choice([1 / 256, 1 / 16, 0.0625, 0.125, 0.25, 0.5]))
    span = float(die.max() - die.min())
    while q > span / 6 and q > 1 / 256:
        q /= 2
    nz = logu(rng, 0.005, 0.2)
    upd = float(rng.choice([0.0, 0.1, 1.0, 2.0]))
    Tm = lag1(ctx.t, die, lag) + off + rng.normal(size=len(die)) * nz
    if upd > 0:
        k = np.floor(ctx.t / upd)
        idx = np.searchsorted(k, k, side='left')
        Tm = Tm[idx]
    Tm = np.round(Tm / q) * q
    p.update(thermometer='on-chip' if onchip else 'board', therm_lag_s=lag, therm_offset_c=off,
             therm_quantum_c=q, therm_noise_c=nz, therm_update_s=upd)
    return Tm


def temp_shape(kind, use_bias=True, use_scale=False, quad=False, grad=False):
    def fn(ctx, rng, gain):
        die, p = temp_profile(ctx, rng, kind)
        Tm = thermometer(ctx, rng, die, p)
        dT = die - die[ctx.hold_mask].mean()
        b = np.zeros((len(die), 3))
        sc = None
        if use_bias:
            tco = rng.normal(size=3) * np.array([1, 1, 2])
            b += np.outer(dT, tco)
            p['tco_rel'] = tco.tolist()
            if quad:
                t2 = rng.normal(size=3) * 0.15
                b += np.outer(dT ** 2, t2)
                p['tco2_rel'] = t2.tolist()
            if grad:
                dd = np.gradient(die, ctx.t)
                g2 = rng.normal(size=3) * 60
                b += np.outer(dd, g2)
                p['tgrad_rel_s'] = g2.tolist()
        if use_scale:
            tcs = rng.normal(size=3)
            sc = gain * np.outer(dT, tcs) * (1.0 if not use_bias else 0.8)
            p['tcs_rel'] = tcs.tolist()
        span = float(die.max() - die.min())
        p['phys_cap_g'] = span * (2.5e-3 if use_bias else 4e-4)
        E = Effect(bias=hold_mean_zero(ctx, gain * b) if use_bias else None, scale=sc, temp=Tm)
        return E, p
    return fn


TEMPERATURE = {
    'selfheat-bias': (temp_shape('selfheat'), {}),
    'ramp-bias-scale': (temp_shape('ramp', use_scale=True), {}),
    'handling-heat-bias': (temp_shape('handheat'), {'rig_p': ['box', 'phone', 'jig']}),
    'hvac-quadratic': (temp_shape('hvac', quad=True), {}),
    'chamber-scale': (temp_shape('chamber', use_bias=False, use_scale=True), {}),
    'gradient-bias': (temp_shape('ramp', grad=True), {}),
}


# ---- scale nonlinearity -------------------------------------------------------
def nl_shape(kind):
    def fn(ctx, rng, gain):
        R = ctx.P['range_g']
        p = {'law': kind}
        if kind == 'quadratic':
            k2 = rng.normal(size=3) * np.array([1, 1, 1.8])
            p['k2_rel'] = k2.tolist()
            nl = lambda u: gain * k2 * u ** 2
        elif kind == 'cubic':
            k3 = -np.abs(rng.normal(size=3)) * rng.choice([1, 1, 1, -1])
            p['k3_rel'] = k3.tolist()
            nl = lambda u: gain * k3 * u ** 3
        elif kind == 'tanh':
            Rs = rng.uniform(1.2, 3.0, 3) * min(R, 4.0) / 2
            c = rng.uniform(0.5, 1.0, 3)
            norm = np.abs(Rs * np.tanh(1 / Rs) - 1)
            p.update(sat_g=Rs.tolist(), weight=c.tolist())
            nl = lambda u: gain * c * (Rs * np.tanh(u / Rs) - u) / norm
        elif kind == 'signed-square':
            k = rng.normal(size=3)
            p['k_abs_rel'] = k.tolist()
            nl = lambda u: gain * k * u * np.abs(u)
        elif kind == 'adc-inl':
            bow = rng.normal(size=3)
            rip = rng.normal(size=3) * rng.uniform(0.2, 0.8)
            per = rng.uniform(0.3, 1.5, 3)
            ph = rng.uniform(0, 2 * math.pi, 3)
            p.update(bow_rel=bow.tolist(), ripple_rel=rip.tolist(), ripple_period_g=per.tolist())
            nl = lambda u: gain * (bow * (R * R - u * u) / 4 + rip * np.sin(2 * math.pi * u / per + ph))
        else:  # mixed
            k2 = rng.normal(size=3) * 0.7
            k3 = rng.normal(size=3) * 0.7
            ax = rng.integers(3)
            k2[ax] *= 3
            p.update(k2_rel=k2.tolist(), k3_rel=k3.tolist(), dominant_axis=int(ax))
            nl = lambda u: gain * (k2 * u ** 2 + k3 * u ** 3)
        return Effect(nl=nl), p
    return fn


NONLIN = {k: (nl_shape(k), {}) for k in ['quadratic', 'cubic', 'tanh', 'signed-square', 'adc-inl', 'mixed']}


# ---- settling -----------------------------------------------------------------
def tau_for(ctx, rng, lo=0.04, hi=0.25):
    return np.array([rng.uniform(lo, hi) * d for d in ctx.S.hold_durs])


def settle_exp_bias(ctx, rng, gain):
    taus = tau_for(ctx, rng)
    amps = rng.normal(size=(ctx.S.n, 3)) * np.array([1, 1, 1.5])
    common = rand_dir(rng) * rng.uniform(0, 1.5)
    amps += common
    k, s = ctx.khold, ctx.since
    b = gain * amps[k] * np.exp(-s / taus[k])[:, None]
    return Effect(bias=b), {'tau_frac_hold': [0.04, 0.25], 'common': common.tolist()}


def settle_ringing(ctx, rng, gain):
    fmax = min(40.0, 0.35 * ctx.P['rate'])
    fr = logu(rng, min(2.0, fmax * 0.5), fmax)
    w = 2 * math.pi * fr
    hmin = min(ctx.S.hold_durs)
    a = max(rng.uniform(4, 10) / hmin, w * rng.uniform(0.01, 0.1))
    axes = rand_unit(rng, ctx.S.n) * np.array([1, 1, 0.3])
    amps = rng.uniform(0.3, 1.0, ctx.S.n)
    k, s = ctx.khold, ctx.since
    x, xd, xdd = damped(s, gain * amps[k], a, w)
    ax = axes[k]
    r = rng.normal(size=3) * rng.uniform(0.01, 0.05)
    return Effect(theta=x[:, None] * ax, dtheta=xd[:, None] * ax, ddtheta=xdd[:, None] * ax, r_s=r), \
        {'freq_hz': fr, 'decay_per_s': a, 'pivot_m': r.tolist(), 'magnitude_is': 'rad of rocking'}


def settle_tilt_creep(ctx, rng, gain):
    taus = tau_for(ctx, rng, 0.05, 0.25)
    th0 = rng.normal(size=(ctx.S.n, 3))
    k, s = ctx.khold, ctx.since
    e = np.exp(-s / taus[k])
    x = gain * th0[k] * e[:, None]
    xd = -x / taus[k][:, None]
    xdd = x / taus[k][:, None] ** 2
    return Effect(theta=x, dtheta=xd, ddtheta=xdd, r_s=np.zeros(3)), {'law': 'exponential tilt creep of the mount'}


def settle_anelastic(ctx, rng, gain):
    taus = tau_for(ctx, rng, 0.05, 0.2)
    fp = np.array([ctx.C_pose[i].T @ Z for i in range(ctx.S.n)])
    df = np.vstack([np.zeros(3), np.diff(fp, axis=0)])
    k, s = ctx.khold, ctx.since
    eps = rng.uniform(0.5, 1.5, 3)
    b = -gain * (df[k] * eps) @ ctx.P['A'].T * np.exp(-s / taus[k])[:, None]
    return Effect(bias=b), {'law': 'anelastic lag proportional to the change of specific force', 'eps_rel': eps.tolist()}


def settle_thermal_relax(ctx, rng, gain):
    v = rand_dir(rng, [1, 1, 2])
    t1 = rng.uniform(0.03, 0.1)
    t2 = rng.uniform(0.15, 0.3)
    c = rng.uniform(0.2, 0.7)
    md = np.array([0.0] + [b - a for a, b in ctx.moves])
    k, s = ctx.khold, ctx.since
    hd = np.array(ctx.S.hold_durs)[k]
    x = md[k] / max(md.max(), 1e-9) * (np.exp(-s / (t1 * hd)) - c * np.exp(-s / (t2 * hd)))
    return Effect(bias=gain * np.outer(x, v)), {'tau1_frac': t1, 'tau2_frac': t2, 'overshoot': c, 'direction': v.tolist()}


def settle_scale_recovery(ctx, rng, gain):
    taus = tau_for(ctx, rng, 0.05, 0.25)
    ds = rng.normal(size=(ctx.S.n, 3)) * 0.5 + rng.normal(size=3)
    k, s = ctx.khold, ctx.since
    return Effect(scale=gain * ds[k] * np.exp(-s / taus[k])[:, None]), {'law': 'scale factor recovery after shock'}


SETTLING = {
    'exp-bias': (settle_exp_bias, {}),
    'mount-ringing': (settle_ringing, {'kinematic': True}),
    'tilt-creep': (settle_tilt_creep, {'kinematic': True}),
    'anelastic-lag': (settle_anelastic, {}),
    'thermal-relaxation': (settle_thermal_relax, {'rig_p': ['box', 'phone', 'jig']}),
    'scale-recovery': (settle_scale_recovery, {}),
}


# ---- motion ---------------------------------------------------------------------
def motion_hand(ctx, rng, gain):
    t = ctx.t
    x1, d1, dd1 = sines(rng, t, 6, 0.1, 1.2, 1.0)
    x2, d2, dd2 = sines(rng, t, 4, 6, min(12, 0.45 * ctx.P['rate']), 0.15)
    th, thd, thdd = gain * (x1 + x2), gain * (d1 + d2), gain * (dd1 + dd2)
    y, yd, ydd = sines(rng, t, 5, 0.2, 3, 1.0)
    acc = gain * ydd * 0.05 / G0
    r = rng.normal(size=3) * 0.08
    return Effect(theta=th, dtheta=thd, ddtheta=thdd, r_s=r, acc_w=acc), {'sway_hz': [0.1, 1.2], 'tremor_hz': [6, 12]}


def motion_table_vib(ctx, rng, gain):
    t = ctx.t
    f0 = rng.uniform(15, 120)
    v = rand_dir(rng, [0.5, 0.5, 1.0])
    ph = rng.uniform(0, 6.28, 3)
    h = np.array([1.0, rng.uniform(0, 0.6), rng.uniform(0, 0.3)])
    a = sum(h[i] * np.sin(2 * math.pi * f0 * (i + 1) * t + ph[i]) for i in range(3))
    return Effect(acc_w=gain * np.outer(a, v)), {'fundamental_hz': f0, 'harmonics': h.tolist(), 'direction_world': v.tolist()}


def motion_bumps(ctx, rng, gain):
    t = ctx.t
    rate = logu(rng, 0.05, 0.5)
    nb = max(2, rng.poisson(rate * ctx.T))
    acc = np.zeros((len(t), 3))
    th = np.zeros((len(t), 3)); thd = np.zeros_like(th); thdd = np.zeros_like(th)
    for _ in range(nb):
        k = rng.integers(ctx.S.n)
        a0, a1 = ctx.S.holds[k]
        tb = rng.uniform(a0, a1)
        fr = rng.uniform(5, min(40, 0.4 * ctx.P['rate']))
        dec = rng.uniform(5, 30)
        amp = rng.uniform(0.3, 1)
        i0 = np.searchsorted(t, tb)
        i1 = np.searchsorted(t, tb + 6 / dec)
        s = t[i0:i1] - tb
        x, xd, xdd = damped(s, 1.0, dec, 2 * math.pi * fr)
        acc[i0:i1] += gain * amp * np.outer(xdd, rand_dir(rng)) / ((2 * math.pi * fr) ** 2)
        ax = rand_dir(rng, [1, 1, 0.3])
        xr, xrd, xrdd = damped(s, 0.02 * gain * amp, dec, 2 * math.pi * fr)
        th[i0:i1] += np.outer(xr, ax); thd[i0:i1] += np.outer(xrd, ax); thdd[i0:i1] += np.outer(xrdd, ax)
    return Effect(acc_w=acc, theta=th, dtheta=thd, ddtheta=thdd, r_s=np.array([0.02, 0.0, 0.0])), \
        {'bumps': int(nb), 'rate_per_s': rate}


def motion_slow_rock(ctx, rng, gain):
    t = ctx.t
    fr = rng.uniform(0.3, 3.0)
    amp_pose = rng.uniform(0, 1, ctx.S.n) ** 2
    ax_pose = rand_unit(rng, ctx.S.n) * np.array([1, 1, 0.2])
    k = ctx.khold
    ph = rng.uniform(0, 6.28)
    mod = 1 + 0.3 * np.sin(2 * math.pi * 0.07 * t)
    x = gain * amp_pose[k] * mod * np.sin(2 * math.pi * fr * t + ph)
    w = 2 * math.pi * fr
    xd = gain * amp_pose[k] * mod * w * np.cos(2 * math.pi * fr * t + ph)
    xdd = -w * w * x
    r = np.array([0, 0, rng.uniform(0.01, 0.05)])
    return Effect(theta=x[:, None] * ax_pose[k], dtheta=xd[:, None] * ax_pose[k], ddtheta=xdd[:, None] * ax_pose[k], r_s=r), \
        {'rock_hz': fr}


def motion_vehicle(ctx, rng, gain):
    t = ctx.t
    x, xd, xdd = sines(rng, t, 5, 0.05, 0.5, 1.0)
    x[:, 2] *= 0.3; xd[:, 2] *= 0.3; xdd[:, 2] *= 0.3
    y, yd, ydd = sines(rng, t, 5, 0.08, 0.6, 1.0)
    acc = ydd * 0.5 / G0
    return Effect(theta=gain * x, dtheta=gain * xd, ddtheta=gain * xdd, r_s=rng.normal(size=3) * 0.5, acc_w=gain * acc), \
        {'band_hz': [0.05, 0.6]}


def motion_servo_hunt(ctx, rng, gain):
    t = ctx.t
    fr = rng.uniform(2, min(15, 0.4 * ctx.P['rate']))
    w = 2 * math.pi * fr
    ax = np.array([1.0, 0, 0])  # outer gimbal axis (world x) seen in the body varies; use world axis
    axb = np.einsum('nji,j->ni', ctx.C, ax)
    env = 0.6 + 0.4 * np.sin(2 * math.pi * rng.uniform(0.02, 0.2) * t)
    jit = colored(rng, len(t), ctx.P['rate'], 'gm', tau=0.2) * 0.3
    x = gain * env * (np.sin(w * t) + jit)
    xdd = -w * w * gain * env * np.sin(w * t)
    xd = gain * env * w * np.cos(w * t)
    r = rng.normal(size=3) * rng.uniform(0.03, 0.15)
    return Effect(theta=x[:, None] * axb, dtheta=xd[:, None] * axb, ddtheta=xdd[:, None] * axb, r_s=r), \
        {'hunt_hz': fr, 'lever_m': r.tolist()}


MOTION = {
    'hand-held': (motion_hand, {'ref': 'mean', 'kinematic': True}),
    'table-vibration': (motion_table_vib, {'ref': 'sample'}),
    'bumps': (motion_bumps, {'ref': 'sample', 'ratio': (0.3, 20), 'kinematic': True}),
    'slow-rock': (motion_slow_rock, {'ref': 'mean', 'kinematic': True}),
    'vehicle-sway': (motion_vehicle, {'ref': 'mean', 'kinematic': True}),
    'servo-hunt': (motion_servo_hunt, {'ref': 'sample', 'rig': 'gimbal', 'kinematic': True}),
}


# ---- colored noise ----------------------------------------------------------------
def cn_shape(kind):
    def fn(ctx, rng, gain):
        N, fs = len(ctx.t), ctx.P['rate']
        p = {'process': kind}
        x = np.zeros((N, 3))
        if kind == 'random-walk':
            for i in range(3):
                x[:, i] = colored(rng, N, fs, 'rw')
        elif kind == 'flicker':
            al = rng.uniform(0.8, 1.3, 3)
            for i in range(3):
                x[:, i] = colored(rng, N, fs, 'flicker', alpha=al[i])
            p['alpha'] = al.tolist()
        elif kind == 'gauss-markov':
            tau = np.exp(rng.uniform(math.log(1), math.log(200), 3))
            for i in range(3):
                x[:, i] = colored(rng, N, fs, 'gm', tau=tau[i])
            p['tau_s'] = tau.tolist()
        elif kind == 'telegraph':
            axes = rng.permutation(3)[:rng.integers(1, 3)]
            p['axes'] = axes.tolist()
            p['dwell_s'] = []
            for i in axes:
                d_up, d_dn = logu(rng, 0.3, 60), logu(rng, 0.3, 60)
                p['dwell_s'].append([d_up, d_dn])
                tt, st = 0.0, rng.integers(2)
                sw = []
                while tt < ctx.T:
                    tt += rng.exponential(d_up if st else d_dn)
                    sw.append(tt)
                    st = 1 - st
                lvl = (np.searchsorted(np.array(sw), ctx.t) + st) % 2
                x[:, i] = lvl * rng.uniform(0.5, 1.0)
        elif kind == 'combo':
            w = rng.uniform(0, 1, 3)
            for i in range(3):
                x[:, i] = (w[0] * colored(rng, N, fs, 'rw') / math.sqrt(ctx.T) + w[1] * colored(rng, N, fs, 'flicker') +
                           w[2] * colored(rng, N, fs, 'gm', tau=logu(rng, 2, 100)))
            p['weights_rw_flicker_gm'] = w.tolist()
        else:  # common-mode
            c = colored(rng, N, fs, str(rng.choice(['flicker', 'gm'])), tau=logu(rng, 2, 100), alpha=1.0)
            v = rand_dir(rng)
            x = np.outer(c, v)
            for i in range(3):
                x[:, i] += 0.3 * colored(rng, N, fs, 'flicker')
            p['direction'] = v.tolist()
        x = x - x[ctx.hold_mask].mean(axis=0)
        return Effect(bias=gain * x), p
    return fn


COLORED = {k: (cn_shape(k), {}) for k in ['random-walk', 'flicker', 'gauss-markov', 'telegraph', 'combo', 'common-mode']}


# ---- out of catalogue (honest) ----------------------------------------------------
def oc_pressed(ctx, rng, gain):
    m = int(rng.choice([1, 1, 2]))
    ks = rng.permutation(ctx.S.n)[:m]
    b = np.zeros((len(ctx.t), 3))
    for k in ks:
        a0, a1 = ctx.S.holds[k]
        sel = (ctx.t >= a0 + 0.05 * (a1 - a0)) & (ctx.t < a1)
        b[sel] += rand_dir(rng)
    return Effect(bias=gain * b), {'poses': ks.tolist(), 'mechanism': 'board flexed by a finger/clip during one hold'}


def oc_step(ctx, rng, gain):
    ts = rng.uniform(0.2, 0.8) * ctx.T
    v = rand_dir(rng)
    b = np.outer((ctx.t >= ts).astype(float), v)
    return Effect(bias=gain * b), {'t_step_s': ts, 'direction': v.tolist(), 'mechanism': 'sudden bias step (charge event / reconfiguration)'}


def oc_hysteresis(ctx, rng, gain):
    u0 = ctx.f_nom @ ctx.P['A'].T
    step = max(1, int(ctx.P['rate'] / 25))
    idx = np.arange(0, len(u0), step)
    w = rng.uniform(0.4, 1.0, 3)
    p = u0[0].copy()
    out = np.empty((len(idx), 3))
    for j, i in enumerate(idx):
        p = np.maximum(u0[i] - w, np.minimum(u0[i] + w, p))
        out[j] = p
    d = np.repeat(out - u0[idx], step, axis=0)[:len(u0)]
    return Effect(bias=gain * d), {'play_rel': w.tolist(), 'mechanism': 'play-operator (backlash) hysteresis: reading depends on approach direction'}


def oc_cross(ctx, rng, gain):
    c = rng.normal(size=(3, 3))
    p = {'c_xy_xz_yz_rel': c.tolist(), 'mechanism': 'bilinear cross-axis coupling f_j*f_k'}
    def post(f, u):
        pr = np.column_stack([f[:, 0] * f[:, 1], f[:, 0] * f[:, 2], f[:, 1] * f[:, 2]])
        return gain * pr @ c.T
    return Effect(post=post), p


def on_intervals(ctx, rng):
    k = int(rng.integers(1, 4))
    on = np.zeros(len(ctx.t), bool)
    iv = []
    for _ in range(k):
        a = rng.uniform(0, 0.9) * ctx.T
        b = min(ctx.T, a + rng.uniform(0.1, 0.4) * ctx.T)
        on |= (ctx.t >= a) & (ctx.t < b)
        iv.append([a, b])
    return on, iv


def oc_emi(ctx, rng, gain):
    on, iv = on_intervals(ctx, rng)
    fm = float(rng.choice([50.0, 60.0])) * (1 + rng.normal() * 2e-4)
    v = rand_dir(rng)
    kdc = rng.uniform(0.05, 0.4)
    ph = rng.uniform(0, 6.28)
    s = np.sin(2 * math.pi * fm * ctx.t + ph) + kdc
    return Effect(bias=gain * np.outer(on * s, v)), {'mains_hz': fm, 'rectified_dc_frac': kdc, 'intervals_s': iv,
                                                   'mechanism': 'mains interference with rectified DC part while a nearby device is on'}


def oc_vre(ctx, rng, gain):
    on, iv = on_intervals(ctx, rng)
    az = rng.uniform(0, 2 * math.pi)
    v = np.array([math.cos(az), math.sin(az), rng.uniform(-0.2, 0.2)])
    vb = np.einsum('nji,j->ni', ctx.C, v)
    k = rng.normal(size=3)
    return Effect(bias=gain * on[:, None] * k * vb ** 2), {'vib_dir_world': v.tolist(), 'k_rel': k.tolist(), 'intervals_s': iv,
                                                         'mechanism': 'vibration rectification of an out-of-band (kHz) horizontal vibration'}


def oc_glitch(ctx, rng, gain):
    N = len(ctx.t)
    frac = logu(rng, 2e-4, 3e-3)
    n = max(3, int(frac * N))
    idx = np.sort(rng.choice(N, n, replace=False))
    ax = rng.integers(0, 3, n)
    sg = rng.choice([-1, 1], n)
    b = np.zeros((N, 3))
    b[idx, ax] = sg
    return Effect(glitch=(idx, ax, sg), glitch_gain=gain, bias=None), \
        {'glitches': int(n), 'mechanism': 'register read glitch (byte tearing): isolated spikes of a fixed size'}, b


def oc_localg(ctx, rng, gain):
    d = rng.uniform(-0.0028, 0.0026)
    return Effect(gl=1.0 + d), {'g_local_rel': d, 'mechanism': 'local gravity differs from standard g (absorbed by the scale factors)'}


HONEST = {
    'pressed-pose': (oc_pressed, {}),
    'bias-step': (oc_step, {}),
    'hysteresis': (oc_hysteresis, {}),
    'cross-coupling': (oc_cross, {}),
    'mains-emi': (oc_emi, {}),
    'hidden-vre': (oc_vre, {}),
    'register-glitch': (oc_glitch, {'ref': 'sample', 'ratio': (3, 60), 'cap_g': 0.5}),
    'local-gravity': (oc_localg, {'fixed': True}),
}

# physical upper bounds of the effect peak (g) per family
FAMILY_CAP_G = {'drift': 0.02, 'temperature': 0.03, 'scale-nonlinearity': 0.02, 'settling': 0.02,
                'motion': 0.15, 'colored-noise': 0.01, 'out-of-catalogue': 0.03}

SHAPES = {'clean': CLEAN, 'drift': DRIFT, 'temperature': TEMPERATURE, 'scale-nonlinearity': NONLIN,
          'settling': SETTLING, 'motion': MOTION, 'colored-noise': COLORED, 'out-of-catalogue': HONEST}


# ----------------------------------------------------------------------------
# one log
# ----------------------------------------------------------------------------
class Ctx:
    pass


def call_shape(fn, ctx, seed, gain):
    r = fn(ctx, np.random.default_rng(seed), gain)
    if len(r) == 3:
        return r[0], r[1], r[2]
    return r[0], r[1], None


def effect_delta(ctx, E, extra):
    """Noise-free change of the sensor output (g) caused by the effect."""
    if extra is not None:
        return extra * E.get('glitch_gain', 1.0)
    u1, _ = sensor_u(ctx, E)
    return u1 - ctx.u_nom


def generate_log(seed, family, index, outdir):
    rng = np.random.default_rng([seed, zlib.crc32(family.encode()), index])
    shapes = SHAPES[family]
    names = list(shapes)
    shape = names[index % len(names)]
    fn, hints = shapes[shape]
    hints = dict(hints)

    # ---- session
    if hints.get('rig'):
        rig = hints['rig']
    elif hints.get('rig_p'):
        rig = str(rng.choice(hints['rig_p']))
    else:
        rig = str(rng.choice(RIGS, p=[0.25, 0.2, 0.2, 0.15, 0.2]))
    if hints.get('poses'):
        n = int(rng.integers(hints['poses'][0], hints['poses'][1] + 1))
    elif rng.random() < 0.4:
        n = int(rng.integers(12, 17))
    else:
        n = int(rng.integers(17, 61) if rig in ('gimbal', 'random', 'jig') else rng.integers(17, 31))
    hlo, hhi = hints.get('hold', (2.5, 20.0))
    hold = logu(rng, hlo, hhi)
    if n > 40:
        hold = min(hold, 10.0)
    S = build_session(rng, rig, n, hold, hints)
    part_hints = dict(hints)
    part_hints['hold_s'] = float(np.median(S.hold_durs))
    part_hints['hold_min_s'] = float(np.min(S.hold_durs))
    P = draw_part(rng, S.T, part_hints)
    fs = P['rate']
    fs_true = fs * (1 + P['clock_ppm'] * 1e-6)
    N = int(S.T * fs_true)
    t = np.arange(N) / fs_true

    ctx = Ctx()
    ctx.S, ctx.P, ctx.t, ctx.T = S, P, t, S.T
    ctx.C, ctx.acc_nom = nominal_kinematics(S, t)
    ctx.C_pose = S.Cs
    hs = np.array([h[0] for h in S.holds])
    he = np.array([h[1] for h in S.holds])
    ctx.khold = np.clip(np.searchsorted(hs, t, side='right') - 1, 0, n - 1)
    ctx.since = t - hs[ctx.khold]
    ctx.hold_mask = t < he[ctx.khold]
    ctx.moves = [(he[i], hs[i + 1]) for i in range(n - 1)]
    ctx.u_nom, ctx.f_nom = sensor_u(ctx, None)

    # ---- noise references
    h = filter_kernel(P)
    ng = math.sqrt(float(np.sum(h ** 2))) if h is not None else 1.0
    nd = P['noise_ug_rthz'] * 1e-6
    sig_s = nd * math.sqrt(fs / 2)
    sig_out = sig_s * ng
    tmed = float(np.median(S.hold_durs))
    var_q = 0.0 if sig_out >= 0.5 * P['lsb_g'] else P['lsb_g'] ** 2 / 12
    sig_mean = math.sqrt(nd ** 2 / (2 * tmed) + var_q)

    # ---- effect with gain scaled to the drawn magnitude
    shape_seed = int(rng.integers(2 ** 62))
    params = {}
    magnitude, unit_ = 0.0, 'mg'
    if family == 'clean':
        E, params, extra = call_shape(fn, ctx, shape_seed, 0.0)
        unit_ = 'none'
        ratio = 0.0
    elif hints.get('fixed'):
        E, params, extra = call_shape(fn, ctx, shape_seed, 1.0)
        d = effect_delta(ctx, E, extra)
        magnitude = float(np.max(np.linalg.norm(d[ctx.hold_mask], axis=1)) * 1000)
        ratio = magnitude / 1000 / sig_mean
    else:
        ref = hints.get('ref', 'mean')
        lo, hi = hints.get('ratio', (0.2, 50.0) if ref == 'mean' else (0.1, 8.0))
        ratio = logu(rng, lo, hi)
        target = ratio * (sig_mean if ref == 'mean' else sig_out)
        target = min(target, hints.get('cap_g', FAMILY_CAP_G.get(family, 0.05)))
        E1, p1, extra1 = call_shape(fn, ctx, shape_seed, 1.0)
        if p1.get('phys_cap_g'):
            target = min(target, p1['phys_cap_g'])

        def peak(g):
            Eg, _, xg = call_shape(fn, ctx, shape_seed, g)
            return float(np.max(np.linalg.norm(effect_delta(ctx, Eg, xg)[ctx.hold_mask], axis=1)))
        pk = float(np.max(np.linalg.norm(effect_delta(ctx, E1, extra1)[ctx.hold_mask], axis=1)))
        gain = target / max(pk, 1e-15)
        if hints.get('kinematic'):
            # rotations are not linear in amplitude: refine (secant on the peak)
            slope = peak(1e-3) / 1e-3
            gain = target / max(slope, 1e-15)
            for _ in range(3):
                pk = peak(gain)
                if abs(pk / target - 1) < 0.01:
                    break
                gain *= target / max(pk, 1e-15)
        E, params, extra = call_shape(fn, ctx, shape_seed, gain)
        params['gain'] = gain
        params['reference'] = ref
        magnitude = target * 1000
    params['ratio_drawn'] = float(ratio)
    params['ratio_to_pose_mean_noise'] = float(magnitude / 1000 / sig_mean)

    if family != 'clean':
        d = effect_delta(ctx, E, extra)[ctx.hold_mask]
        nrm = np.linalg.norm(d, axis=1)
        params['effect_peak_mg'] = float(nrm.max() * 1000)
        params['effect_rms_mg'] = float(math.sqrt(np.mean(nrm ** 2)) * 1000)
    else:
        params['effect_peak_mg'] = 0.0
        params['effect_rms_mg'] = 0.0

    # ---- sensor output
    noise = rng.normal(size=(N, 3)) * sig_s
    u, f = sensor_u(ctx, E, noise)
    u = apply_filter(u, h)
    R = P['range_g']
    lsb = P['lsb_g']
    codes = np.round(np.clip(u, -R, R) / lsb)
    codes = np.clip(codes, -2 ** (P['bits'] - 1), 2 ** (P['bits'] - 1) - 1)
    if E.get('glitch') is not None:
        idx, ax, sg = E['glitch']
        codes[idx, ax] += sg * np.round(E['glitch_gain'] / lsb)
        codes = np.clip(codes, -2 ** (P['bits'] - 1), 2 ** (P['bits'] - 1) - 1)
    clipped = float(np.mean(np.any(np.abs(u) >= R, axis=1)))

    # ---- temperature column
    temp = E.get('temp')
    if temp is None and rng.random() < hints.get('flat_temp', 0.25):
        room = rng.uniform(19, 31)
        q = float(rng.choice([0.0625, 0.125, 0.25, 0.01]))
        temp = np.round((room + rng.normal(size=N) * logu(rng, 0.003, 0.05)) / q) * q

    # ---- timestamps
    tn = np.arange(N)
    if P['timing'] == 'counter':
        tw = P['t_start'] + tn / fs
    elif P['timing'] == 'host':
        tw = P['t_start'] + t + rng.normal(size=N) * P['jitter_s']
    else:
        K = P['fifo_batch']
        last = np.minimum((tn // K) * K + K - 1, N - 1)
        lat = rng.uniform(0.0005, 0.006, N // K + 1)[tn // K]
        # the FIFO is read in bursts of K samples; the logger stamps the burst with the host
        # read time and back-fills the earlier samples at the nominal period
        tw = P['t_start'] + t[last] + lat - (last - tn) / fs
    eps = 1e-6
    tw = np.maximum.accumulate(tw - tn * eps) + tn * eps
    keep = np.ones(N, bool)
    for _ in range(P['drops']):
        a = int(rng.integers(0, N))
        keep[a:a + int(rng.integers(1, max(2, int(0.15 * fs))))] = False
    # hold intervals in the logged time base
    hold_idx = [(int(np.searchsorted(t, a)), int(np.searchsorted(t, b)) - 1) for a, b in S.holds]
    holds_logged = [[round(float(tw[i0]), 6), round(float(tw[min(i1, N - 1)]), 6)] for i0, i1 in hold_idx]
    tw, codes = tw[keep], codes[keep]
    if temp is not None:
        temp = temp[keep]

    # ---- write
    units = P['units']
    if units == 'counts':
        header = ['t', 'ax', 'ay', 'az']
        vals = codes.astype(np.int64)
        vfmt = '%d'
    else:
        scale = {'g': lsb, 'mg': lsb * 1000, 'mps2': lsb * G0}[units]
        vals = codes * scale
        dec = max(3, int(math.ceil(-math.log10(scale))) + 2)
        vfmt = '%.' + str(dec) + 'f'
        header = {'g': ['t', 'ax_g', 'ay_g', 'az_g'], 'mg': ['t', 'ax_mg', 'ay_mg', 'az_mg'],
                  'mps2': ['t', 'ax (m/s^2)', 'ay (m/s^2)', 'az (m/s^2)']}[units]
    fmt = '%.6f,' + ','.join([vfmt] * 3)
    if temp is not None:
        header = header + ['temp']
        fmt += ',%.4f'
    name = '%s_%03d_%s.csv' % (family, index, shape)
    path = os.path.join(outdir, name)
    with open(path, 'w', newline='\n') as fh:
        fh.write(','.join(header) + '\n')
        if units == 'counts':
            vi = vals.tolist()
            if temp is not None:
                fh.write('\n'.join(fmt % (a, b[0], b[1], b[2], c) for a, b, c in zip(tw.tolist(), vi, temp.tolist())))
            else:
                fh.write('\n'.join(fmt % (a, b[0], b[1], b[2]) for a, b in zip(tw.tolist(), vi)))
        else:
            arr = np.column_stack([tw, vals] + ([temp] if temp is not None else []))
            fh.write('\n'.join(fmt % tuple(r) for r in arr.tolist()))
        fh.write('\n')

    flt = dict(P['filter'])
    part = {'rate_hz': fs, 'noise_ug_rthz': P['noise_ug_rthz'], 'bits': P['bits'], 'range_g': R,
            'lsb_g': lsb, 'filter': flt, 'units': units, 'A': P['A'].tolist(),
            'b_mg': (P['b'] * 1000).tolist(), 'timing': P['timing'], 'clock_ppm': P['clock_ppm'],
            'jitter_s': P['jitter_s'], 'fifo_batch': P['fifo_batch'], 'drops': P['drops'],
            'sample_noise_mg': sig_out * 1000, 'pose_mean_noise_mg': sig_mean * 1000,
            'clipped_fraction': clipped}
    params = jsonable(params)
    return {
        'file': name, 'family': family, 'shape': shape,
        'expected': EXPECTED.get(family, family), 'seed': seed, 'index': index,
        'magnitude': float(magnitude), 'magnitude_unit': unit_ if family != 'clean' else 'none',
        'poses': n, 'duration_s': float(tw[-1] - tw[0]), 'rows': int(len(tw)),
        'rig': rig, 'move_style': S.style, 'lever_m': S.lever.tolist(),
        'hold_s_median': tmed, 'has_temp': temp is not None, 'holds_t': holds_logged,
        'params': params, 'part': part,
    }


def jsonable(x):
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    return x


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--out', required=True)
    ap.add_argument('--per-family', type=int, default=12)
    ap.add_argument('--seed', type=int, required=True)
    ap.add_argument('--families', default=','.join(FAMILIES))
    ap.add_argument('--quiet', action='store_true')
    a = ap.parse_args(argv)
    fams = [f.strip() for f in a.families.split(',') if f.strip()]
    for f in fams:
        if f not in SHAPES:
            ap.error('unknown family %r (known: %s)' % (f, ', '.join(FAMILIES)))
    os.makedirs(a.out, exist_ok=True)
    man = []
    t0 = time.time()
    for f in fams:
        for i in range(a.per_family):
            m = generate_log(a.seed, f, i, a.out)
            man.append(m)
            if not a.quiet:
                print('%-45s %7d rows %6.1f s  %s' % (m['file'], m['rows'], m['duration_s'], m['rig']), file=sys.stderr)
    with open(os.path.join(a.out, 'manifest.json'), 'w') as fh:
        json.dump(man, fh, indent=1)
    if not a.quiet:
        print('%d logs in %.1f s' % (len(man), time.time() - t0), file=sys.stderr)


if __name__ == '__main__':
    main()
