"""The measurement chain of blindgen3: body motion -> specific force -> MEMS part -> digital
low-pass at the internal rate -> output data rate -> quantiser -> read-out (FIFO or polling)
-> CSV.

Internal rate: the part's sense path is simulated at fs = k * ODR_true (k = 2..8), the ODR
coming from the part's own oscillator (nominal ODR +- its tolerance). The digital low-pass
is a 2nd-order Butterworth at the configured bandwidth, applied in the frequency domain
(exact analogue response, edges padded) and the output register takes every k-th sample.
"""

import numpy as np

from parts import G0
from session import exp_so3

MAX_INTERNAL = 1_600_000


class Ctx:
    """Everything an injector may read (t, fs, holds, poses, R, T_die, unit) or add to
    (dtheta, dp, bias, scale, nonlin, noise); see effects.py."""

    def __init__(self, t, fs, segs, st, R, P, T_die, unit):
        self.t, self.fs, self.segs = t, fs, segs
        self.holds = [(a, b, k) for kind, a, b, k in segs if kind == "hold"]
        self.poses = st["poses"]
        self.lever = st["lever_m"]
        self.R, self.P, self.T_die, self.unit = R, P, T_die, unit
        n = len(t)
        self.dtheta = np.zeros((n, 3))
        self.dp = np.zeros((n, 3))
        self.bias = np.zeros((n, 3))
        self.scale = np.zeros((n, 3))
        self.nonlin = []
        self.noise = np.zeros((n, 3))

    def hold_mask(self, trim=0.0):
        m = np.zeros(len(self.t), bool)
        for a, b, _ in self.holds:
            m |= (self.t >= a + trim) & (self.t < b - trim)
        return m


def specific_force(ctx, perturbed=True, g_local=G0):
    """Specific force in the body frame, m/s^2: R^T (p'' + g e_z), p = pivot + dp + R lever."""
    R = ctx.R
    P = ctx.P
    if perturbed and np.any(ctx.dtheta):
        R = exp_so3(ctx.dtheta) @ R
    if perturbed:
        P = P + ctx.dp
    p = P + R @ ctx.lever
    dt = 1 / ctx.fs
    acc = np.zeros_like(p)
    acc[1:-1] = (p[2:] - 2 * p[1:-1] + p[:-2]) / dt ** 2
    acc[0], acc[-1] = acc[1], acc[-2]
    acc[:, 2] += g_local
    return np.einsum("nji,nj->ni", R, acc)


def sensed(ctx, f_body, effects=True):
    """Sensor output before noise, g: gain (Ka-like: sensitivity, cross-axis, mounting)
    applied to the sensed specific force plus the zero-g offset; with effects, the injected
    scale, non-linear terms and offsets act on the sensing element first."""
    a = f_body / G0
    if effects:
        extra = a * ctx.scale
        for fn in ctx.nonlin:
            extra = extra + fn(a)
        a = a + extra + ctx.bias
    u = ctx.unit
    return a @ u["gain"].T + u["offset_g"][None]


def lowpass(x, fs, fc):
    """2nd-order Butterworth low-pass (cut-off fc, Hz) of x (N,3) sampled at fs, via FFT with
    the edges padded by their end values (10 time constants each side)."""
    npad = int(10 * fs / (2 * np.pi * fc)) + 16
    xp = np.pad(x, ((npad, npad), (0, 0)), mode="edge")
    n = len(xp)
    f = np.fft.rfftfreq(n, 1 / fs)
    s = 1j * f / fc
    H = 1 / (1 + np.sqrt(2) * s + s * s)
    y = np.fft.irfft(np.fft.rfft(xp, axis=0) * H[:, None], n, axis=0)
    return y[npad:npad + len(x)]


def white_std(nd_g, fs):
    """Per-sample std (g) of white noise of one-sided density nd_g (g/sqrt(Hz)) at rate fs."""
    return nd_g * np.sqrt(fs / 2)


def run_part(ctx, rng):
    """Return (t_out, y_out_g, idx, magnitude_mg): the part's output register samples
    (before quantisation), their internal indices, and the injected effect's size: RMS over
    hold samples (first 0.5 s of each hold included) of the effect's change of the output
    after the low-pass, its hold mean removed, vector norm, mg."""
    u = ctx.unit
    f1 = specific_force(ctx, True)
    y1 = sensed(ctx, f1, True) + ctx.noise
    f0 = specific_force(ctx, False) if (np.any(ctx.dtheta) or np.any(ctx.dp)) else f1
    y0 = sensed(ctx, f0, False)
    y = y1 + rng.normal(size=y1.shape) * white_std(u["nd_g"], ctx.fs)
    yf = lowpass(y, ctx.fs, u["bw_hz"])
    d = lowpass(y1 - y0, ctx.fs, u["bw_hz"])
    hm = ctx.hold_mask()
    dd = d[hm] - d[hm].mean(0)
    mag = float(np.sqrt(np.mean(np.sum(dd ** 2, 1)))) * 1e3
    k = ctx.k
    idx = np.arange(k - 1, len(ctx.t), k)
    return ctx.t[idx], yf[idx], idx, mag


def quantise(y_g, unit):
    """Clip to the full scale and round to output codes (integer counts)."""
    lim = 2 ** (unit["bits"] - 1)
    c = np.round(y_g * unit["lsb_per_g"])
    return np.clip(c, -lim, lim - 1).astype(np.int64)


def strictly_increasing(s, min_step=2e-6):
    """Host stamps made strictly increasing (a logger never writes time backwards): any step
    below min_step (s) is raised to it."""
    d = np.maximum(np.diff(s), min_step)
    return s[0] + np.concatenate([[0.0], np.cumsum(d)])


def readout(rng, t_s, odr_nom, mode):
    """Host read-out of the sample stream t_s (sensor times, s).

    Returns (host timestamps, indices into the sensor stream, info):
      poll        the host polls the data register at its own nominal-ODR clock (+-200 ppm),
                  jitter 0.02-0.3 ms, stalls of 5-60 ms every 20-200 s; a poll returns the
                  latest sample, so the ODR mismatch duplicates or skips samples.
      fifo-count  every sample is read from the FIFO and stamped n/ODR_nom; now and then
                  (every 60-600 s) the FIFO overflows during a host stall and 10-100 samples
                  are lost without a trace in the stamps.
      fifo-batch  FIFO read in bursts of 8-32 samples; each burst stamped on arrival (host
                  clock, 0.5-3 ms latency, jitter) and back-filled at 1/ODR_nom, made
                  monotonic.
    """
    T = t_s[-1]
    info = dict(mode=mode)
    if mode == "poll":
        eps = rng.uniform(-2e-4, 2e-4)
        jit = rng.uniform(2e-5, 3e-4)
        n = int(T * odr_nom * 1.1) + 10
        dt = np.full(n, (1 + eps) / odr_nom) + rng.normal(0, jit, n) * 0.3
        every = rng.uniform(20, 200)
        ns = rng.poisson(T / every)
        dt[rng.integers(0, n, ns)] += rng.uniform(5e-3, 60e-3, ns)
        tau = t_s[0] + rng.uniform(0, 1 / odr_nom) + np.cumsum(np.maximum(dt, 1e-5))
        tau = tau[tau <= T]
        idx = np.searchsorted(t_s, tau, side="right") - 1
        keep = idx >= 0
        tau, idx = tau[keep], idx[keep]
        stamps = tau + rng.normal(0, jit, len(tau)) * 0.2
        stamps = strictly_increasing(stamps)
        info.update(duplicates=int(np.sum(np.diff(idx) == 0)), skipped=int(np.sum(np.diff(idx) > 1)))
        return stamps, idx, info
    idx = np.arange(len(t_s))
    if mode == "fifo-count":
        every = rng.uniform(60, 600)
        lost = 0
        for _ in range(rng.poisson(T / every)):
            a = int(rng.integers(0, len(idx)))
            b = a + int(rng.integers(10, 100))
            lost += len(idx[a:b])
            idx = np.concatenate([idx[:a], idx[b:]])
        info.update(lost=lost)
        return np.arange(len(idx)) / odr_nom, idx, info
    m = int(rng.integers(8, 33))
    lat = rng.uniform(5e-4, 3e-3)
    stamps = np.empty(len(idx))
    for b0 in range(0, len(idx), m):
        b1 = min(len(idx), b0 + m)
        arr = t_s[b1 - 1] + lat + abs(rng.normal(0, 2e-4))
        stamps[b0:b1] = arr - (b1 - 1 - np.arange(b0, b1)) / odr_nom
    stamps = strictly_increasing(stamps)
    info.update(batch=m)
    return stamps, idx, info
