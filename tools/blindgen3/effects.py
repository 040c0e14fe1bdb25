"""Injectors of blindgen3: the physical effects beyond the 9-parameter static model.

Every injector is `f(ctx, rng, lvl) -> dict of its drawn parameters`. `lvl` in [0,1] places
the effect's size log-uniformly inside the physical range named in the docstring (0: the
small end, barely above what a datasheet would call typical; 1: the large end, a bad unit
or a careless session). An injector acts on one of four places of the simulated chain
(see chain.py), all at the sensor's internal rate ctx.fs:
  ctx.dtheta (N,3) rad   small extra rotation of the body (world frame): tilts, wobble;
  ctx.dp     (N,3) m     extra displacement of the body (world frame): vibration, taps;
  ctx.bias   (N,3) g     extra zero-g offset along the sensor axes;
  ctx.scale  (N,3) 1     extra relative sensitivity along the sensor axes;
  ctx.nonlin [fn]        a -> extra specific force (g) as a function of the sensed one (g);
  ctx.noise  (N,3) g     extra noise added before the digital low-pass.
Time is s, temperature degC, specific force g (1 g = 9.80665 m/s^2), 1 mg = 1e-3 g.
"""

import numpy as np

from session import min_jerk

G0 = 9.80665
DEG = np.pi / 180


def logi(lo, hi, lvl):
    """Log-interpolate between lo and hi (both > 0) at lvl in [0,1]."""
    return float(np.exp(np.log(lo) + (np.log(hi) - np.log(lo)) * lvl))


def unit_vec(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def horiz_vec(rng):
    a = rng.uniform(0, 2 * np.pi)
    return np.array([np.cos(a), np.sin(a), 0.0])


def hold_levels(ctx, vals):
    """(N,3) signal equal to vals[h] during hold h, moving between neighbours with a
    minimum-jerk profile during each move (so the body or the part changes smoothly)."""
    out = np.zeros((len(ctx.t), 3))
    holds = ctx.holds
    for h, (t0, t1, _) in enumerate(holds):
        m = (ctx.t >= t0) & (ctx.t < t1)
        out[m] = vals[h]
        if h + 1 < len(holds):
            n0, n1 = t1, holds[h + 1][0]
            mm = (ctx.t >= n0) & (ctx.t < n1)
            s = min_jerk((ctx.t[mm] - n0) / (n1 - n0))[:, None]
            out[mm] = vals[h] * (1 - s) + vals[h + 1] * s
    out[ctx.t >= holds[-1][1]] = vals[-1]
    return out


def shaped_noise(rng, n, fs, amp_fn):
    """Gaussian noise of n samples at fs whose one-sided PSD is |amp_fn(f)|^2 (units^2/Hz).
    Synthesised in the frequency domain on twice the length (the second half is dropped,
    so the result is not periodic)."""
    m = 2 * n
    f = np.fft.rfftfreq(m, 1 / fs)
    a = np.zeros_like(f)
    a[1:] = amp_fn(f[1:])
    spec = (rng.normal(size=len(f)) + 1j * rng.normal(size=len(f))) * a * np.sqrt(fs * m / 4)
    spec[0] = 0
    x = np.fft.irfft(spec, m)
    return x[:n]


def lag1(x, fs, tau):
    """First-order lag (time constant tau, s) of a slow signal x sampled at fs, started at x[0].
    Computed on a 10 Hz sub-grid and interpolated back (x is slow by construction)."""
    step = max(1, int(fs / 10))
    xs = x[::step]
    a = np.exp(-step / fs / tau)
    y = np.empty_like(xs)
    y[0] = xs[0]
    for i in range(1, len(xs)):
        y[i] = a * y[i - 1] + (1 - a) * xs[i]
    ti = np.arange(len(x))
    return np.interp(ti, ti[::step], y)


# ================================================================== temperature
def temp_bias(ctx, rng, lvl):
    """Zero-g offset linear in the die temperature: b_i = c_i (T - T_start).
    |c| 0.01-0.5 mg/K per axis (datasheet TCO typ 0.15-0.5 mg/K; the axes differ by 0.3-1x,
    random signs). No lag: the die thermometer reads the temperature that stresses the part."""
    c = logi(0.01, 0.5, lvl) * rng.uniform(0.3, 1, 3) * rng.choice([-1, 1], 3) * 1e-3
    dT = ctx.T_die - ctx.T_die[0]
    ctx.bias += dT[:, None] * c[None]
    return dict(tco_mg_per_k=(c * 1e3).round(4).tolist())


def temp_scale(ctx, rng, lvl):
    """Sensitivity linear in the die temperature: s_i = k_i (T - T_start),
    |k| 0.002-0.06 %/K per axis (datasheet TCS 0.002-0.05 %/K)."""
    k = logi(0.002, 0.06, lvl) * rng.uniform(0.3, 1, 3) * rng.choice([-1, 1], 3) / 100
    dT = ctx.T_die - ctx.T_die[0]
    ctx.scale += dT[:, None] * k[None]
    return dict(tcs_pct_per_k=(k * 100).round(5).tolist())


def temp_bias_scale(ctx, rng, lvl):
    """Both: offset 0.01-0.4 mg/K and sensitivity 0.002-0.04 %/K, from the same die temperature."""
    p = temp_bias(ctx, rng, lvl * 0.9)
    p.update(temp_scale(ctx, rng, lvl * 0.9))
    return p


def temp_bias_lagged(ctx, rng, lvl):
    """Offset driven by the package/board temperature, which lags the logged die temperature
    through a first-order lag tau 30-300 s (heat flows die -> mould compound -> PCB): b_i =
    c_i (T_lag - T_lag(0)), |c| 0.01-0.5 mg/K."""
    tau = rng.uniform(30, 300)
    c = logi(0.01, 0.5, lvl) * rng.uniform(0.3, 1, 3) * rng.choice([-1, 1], 3) * 1e-3
    Tl = lag1(ctx.T_die, ctx.fs, tau)
    ctx.bias += (Tl - Tl[0])[:, None] * c[None]
    return dict(tco_mg_per_k=(c * 1e3).round(4).tolist(), lag_tau_s=round(tau, 1))


def temp_bias_quadratic(ctx, rng, lvl):
    """Offset-vs-temperature curve with curvature (a parabola with its vertex near room
    temperature, as in datasheet TCO plots): b_i = c1_i dT + c2_i dT^2,
    |c1| 0.005-0.1 mg/K, |c2| 0.002-0.05 mg/K^2, dT = T - T_start."""
    c1 = logi(0.005, 0.1, lvl) * rng.uniform(-1, 1, 3) * 1e-3
    c2 = logi(0.002, 0.05, lvl) * rng.uniform(0.3, 1, 3) * rng.choice([-1, 1], 3) * 1e-3
    dT = (ctx.T_die - ctx.T_die[0])[:, None]
    ctx.bias += c1[None] * dT + c2[None] * dT ** 2
    return dict(c1_mg_per_k=(c1 * 1e3).round(4).tolist(), c2_mg_per_k2=(c2 * 1e3).round(5).tolist())


# ================================================================== drift (time, not temperature)
def _drift_dir(rng, total_mg):
    return unit_vec(rng) * total_mg * 1e-3


def drift_linear(ctx, rng, lvl):
    """Offset ramp at constant rate (charge build-up in the sense capacitors, solder/glue stress
    relaxation over hours seen as a ramp over the session): total change 0.05-5 mg over the
    log, along a random sensor direction."""
    d = _drift_dir(rng, logi(0.05, 5, lvl))
    ctx.bias += (ctx.t / ctx.t[-1])[:, None] * d[None]
    return dict(total_mg=round(float(np.linalg.norm(d) * 1e3), 4))


def drift_log_creep(ctx, rng, lvl):
    """Logarithmic creep of the die attach after a recent board mount/flex:
    b = D log(1 + t/t0) / log(1 + T/t0), t0 5-60 s, total D 0.05-5 mg."""
    t0 = rng.uniform(5, 60)
    d = _drift_dir(rng, logi(0.05, 5, lvl))
    s = np.log1p(ctx.t / t0) / np.log1p(ctx.t[-1] / t0)
    ctx.bias += s[:, None] * d[None]
    return dict(total_mg=round(float(np.linalg.norm(d) * 1e3), 4), t0_s=round(t0, 1))


def drift_exp_relax(ctx, rng, lvl):
    """Offset relaxing exponentially to a new value (dielectric absorption / trapped charge
    after power-up of a part already at temperature): b = D (1 - exp(-t/tau)),
    tau 0.15-0.8 of the log length, D 0.05-5 mg."""
    tau = rng.uniform(0.15, 0.8) * ctx.t[-1]
    d = _drift_dir(rng, logi(0.05, 5, lvl))
    ctx.bias += (1 - np.exp(-ctx.t / tau))[:, None] * d[None]
    return dict(total_mg=round(float(np.linalg.norm(d) * 1e3), 4), tau_s=round(tau, 1))


def drift_supply_sag(ctx, rng, lvl):
    """Ratiometric analogue front end read by an ADC with its own reference, supply from a
    discharging cell: relative supply e(t) = -delta t/T, delta 0.005-0.2 %. Sensitivity
    scales with e, and the zero-g level (Vs/2 with 0.1 Vs/g sensitivity, i.e. 5 g) moves
    by 5 g * e (times a 0.02-0.1 trim mismatch per axis)."""
    delta = logi(0.005, 0.2, lvl) / 100
    e = -delta * ctx.t / ctx.t[-1]
    mis = rng.uniform(0.02, 0.1, 3) * rng.choice([-1, 1], 3)
    ctx.scale += e[:, None] * np.ones(3)[None]
    ctx.bias += (5.0 * e)[:, None] * mis[None]
    return dict(delta_pct=round(delta * 100, 5), offset_mismatch=mis.round(4).tolist())


# ================================================================== scale non-linearity
def _nl(ctx, rng, lvl, k2on, k3on, axes=(0, 1, 2)):
    """Per-axis polynomial in the specific force along that axis: a_i + k2_i a_i^2 + k3_i a_i^3.
    The deviation at |a| = 1 g, |k| 0.1-8 mg (datasheet non-linearity 0.1-1 %FS at 2-8 g FS
    is 2-80 mg at full scale; a quadratic/cubic bow scaled to 1 g gives this range)."""
    k2 = np.zeros(3)
    k3 = np.zeros(3)
    for i in axes:
        if k2on:
            k2[i] = logi(0.1, 8, lvl) * rng.uniform(0.5, 1) * rng.choice([-1, 1]) * 1e-3
        if k3on:
            k3[i] = logi(0.1, 8, lvl) * rng.uniform(0.5, 1) * rng.choice([-1, 1]) * 1e-3
    ctx.nonlin.append(lambda a, k2=k2, k3=k3: k2[None] * a ** 2 + k3[None] * a ** 3)
    return dict(k2_mg_per_g2=(k2 * 1e3).round(4).tolist(), k3_mg_per_g3=(k3 * 1e3).round(4).tolist())


def nl_quadratic(ctx, rng, lvl):
    """Even (asymmetric) bow: proof-mass/electrode asymmetry; k2 a^2 per axis, 0.1-8 mg at 1 g."""
    return _nl(ctx, rng, lvl, True, False)


def nl_cubic(ctx, rng, lvl):
    """Odd bow: electrostatic spring softening / 1/d^2 force law; k3 a^3 per axis, 0.1-8 mg at 1 g."""
    return _nl(ctx, rng, lvl, False, True)


def nl_mixed(ctx, rng, lvl):
    """Both k2 and k3 on every axis, 0.1-8 mg at 1 g each."""
    return _nl(ctx, rng, lvl, True, True)


def nl_z_only(ctx, rng, lvl):
    """Only the out-of-plane (z) axis bows (vertical comb / plate sensing, the worst axis of
    most parts): k2 and k3 on z, 0.1-8 mg at 1 g."""
    return _nl(ctx, rng, lvl, True, True, axes=(2,))


# ================================================================== settling
def settle_creep_tilt(ctx, rng, lvl):
    """Viscoelastic creep of the support (foam, rubber feet, book spine) after each placement:
    the body keeps tilting by theta0 exp(-t/tau) about a random horizontal axis,
    theta0 0.01-1 deg (x 0.5-1 per hold), tau 0.5-4 s (at most a third of the hold).
    The offset is built up during the last 0.5 s of the move (hand lowering it), so the
    attitude is continuous."""
    th0 = logi(0.01, 1.0, lvl) * DEG
    tau = rng.uniform(0.5, 4.0)
    for h, (t0, t1, _) in enumerate(ctx.holds):
        u = horiz_vec(rng) * th0 * rng.uniform(0.5, 1)
        ta = min(tau, (t1 - t0) / 3)
        m = (ctx.t >= t0) & (ctx.t < t1)
        ctx.dtheta[m] += np.exp(-(ctx.t[m] - t0) / ta)[:, None] * u[None]
        if h > 0:
            r0 = max(ctx.holds[h - 1][1], t0 - 0.5)
            mm = (ctx.t >= r0) & (ctx.t < t0)
            ctx.dtheta[mm] += min_jerk((ctx.t[mm] - r0) / (t0 - r0))[:, None] * u[None]
    return dict(theta0_deg=round(th0 / DEG, 4), tau_s=round(tau, 2))


def settle_ringing(ctx, rng, lvl):
    """Structural ringing after each stop (gimbal arm, cantilevered jig, springy table top):
    a damped rotation theta0 exp(-zeta w t) sin(w_d t) about a random axis, f 3-25 Hz,
    zeta 0.01-0.1, theta0 0.02-1 deg; the lever arm turns it into tangential acceleration too."""
    f = rng.uniform(3, 25)
    z = rng.uniform(0.01, 0.1)
    th0 = logi(0.02, 1.0, lvl) * DEG
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - z * z)
    for t0, t1, _ in ctx.holds[1:]:
        u = unit_vec(rng) * th0
        m = (ctx.t >= t0) & (ctx.t < t1)
        x = ctx.t[m] - t0
        ctx.dtheta[m] += (np.exp(-z * w * x) * np.sin(wd * x))[:, None] * u[None]
    return dict(freq_hz=round(f, 2), zeta=round(z, 3), theta0_deg=round(th0 / DEG, 4))


def settle_bias_recovery(ctx, rng, lvl):
    """Offset transient after each placement (package stress released by the set-down shock,
    charge redistribution): b = A v exp(-t/tau) from the hold's start, A 0.1-10 mg (x 0.5-1
    per hold), fixed sensor-frame direction v, tau 0.3-3 s."""
    A = logi(0.1, 10, lvl) * 1e-3
    tau = rng.uniform(0.3, 3.0)
    v = unit_vec(rng)
    for t0, t1, _ in ctx.holds[1:]:
        m = (ctx.t >= t0) & (ctx.t < t1)
        ctx.bias[m] += (A * rng.uniform(0.5, 1) * np.exp(-(ctx.t[m] - t0) / tau))[:, None] * v[None]
    return dict(amp_mg=round(A * 1e3, 4), tau_s=round(tau, 2))


def settle_thermal_touch(ctx, rng, lvl):
    """The operator's hand warms one side of the board during each move; after release the
    thermal gradient across the package decays and its stress-induced offset with it:
    b = A v exp(-t/tau), A 0.1-5 mg, tau 3-15 s (thermal, slower than the mechanical)."""
    A = logi(0.1, 5, lvl) * 1e-3
    tau = rng.uniform(3, 15)
    v = unit_vec(rng)
    for t0, t1, _ in ctx.holds[1:]:
        m = (ctx.t >= t0) & (ctx.t < t1)
        ctx.bias[m] += (A * rng.uniform(0.5, 1) * np.exp(-(ctx.t[m] - t0) / tau))[:, None] * v[None]
    return dict(amp_mg=round(A * 1e3, 4), tau_s=round(tau, 2))


# ================================================================== motion during holds
def _window(ctx, edge=0.3):
    """1 inside holds, 0 in moves, raised-cosine edges of `edge` s inside each hold."""
    w = np.zeros(len(ctx.t))
    for t0, t1, _ in ctx.holds:
        m = (ctx.t >= t0) & (ctx.t < t1)
        x = ctx.t[m]
        e = min(edge, (t1 - t0) / 4)
        w[m] = np.clip(np.minimum(x - t0, t1 - x) / e, 0, 1)
    return 0.5 - 0.5 * np.cos(np.pi * w)


def motion_taps(ctx, rng, lvl):
    """Knocks on the table (typing, a cup set down): Poisson, 1 per 4-20 s of hold; each a
    damped translation of the table top, f 10-40 Hz, zeta 0.05-0.2, peak acceleration
    5-300 mg (x 0.3-1 per tap), mostly vertical."""
    rate = 1 / rng.uniform(4, 20)
    A = logi(5, 300, lvl) * 1e-3 * G0
    f = rng.uniform(10, 40)
    z = rng.uniform(0.05, 0.2)
    w = 2 * np.pi * f
    n = 0
    for t0, t1, _ in ctx.holds:
        k = rng.poisson(rate * (t1 - t0))
        for tt in rng.uniform(t0 + 0.2, max(t0 + 0.3, t1 - 0.5), k):
            d = np.array([*(rng.normal(0, 0.3, 2)), 1.0])
            d /= np.linalg.norm(d)
            m = (ctx.t >= tt) & (ctx.t < tt + 5 / (z * w))
            x = ctx.t[m] - tt
            # displacement whose acceleration peaks near A: x(t) = -(A/w^2) e^{-zwt} sin(w t)
            ctx.dp[m] += (-(A * rng.uniform(0.3, 1) / w ** 2) * np.exp(-z * w * x) * np.sin(w * x))[:, None] * d[None]
            n += 1
    return dict(rate_per_s=round(rate, 4), peak_mg=round(A / G0 * 1e3, 3), freq_hz=round(f, 2), taps=n)


def motion_hand_held(ctx, rng, lvl):
    """The holds are hand-held (phone held still in the air): attitude sway 0.3-3 Hz
    (band-limited, sigma 0.02-1 deg) and physiological tremor 8-12 Hz (translation,
    sigma 1-30 mg of acceleration); both windowed to the holds."""
    sway = logi(0.02, 1.0, lvl) * DEG
    trem = logi(1, 30, lvl) * 1e-3 * G0
    n = len(ctx.t)
    f_lo, f_hi = 0.3, 3.0
    band = lambda f: ((f > f_lo) & (f < f_hi)).astype(float)
    th = np.stack([shaped_noise(rng, n, ctx.fs, band) for _ in range(3)], 1)
    th *= sway / th.std()
    fc = rng.uniform(8, 12)
    tb = lambda f: np.exp(-0.5 * ((f - fc) / 1.0) ** 2)
    acc = np.stack([shaped_noise(rng, n, ctx.fs, tb) for _ in range(3)], 1)
    # displacement of a narrow-band acceleration: divide by (2 pi fc)^2
    disp = -acc / acc.std() * trem / (2 * np.pi * fc) ** 2
    w = _window(ctx)[:, None]
    ctx.dtheta += th * w
    ctx.dp += disp * w
    return dict(sway_deg=round(sway / DEG, 4), tremor_mg=round(trem / G0 * 1e3, 3), tremor_hz=round(fc, 2))


def motion_nudge(ctx, rng, lvl):
    """The body is nudged (elbow, cable pull) in 30-70 % of the holds: a rotation step of
    0.05-3 deg about a random axis within 0.1-0.4 s at a random time in the hold's middle
    60 %; the body stays there until the next move (where the step is undone smoothly)."""
    th = logi(0.05, 3.0, lvl) * DEG
    frac = rng.uniform(0.3, 0.7)
    vals = np.zeros((len(ctx.holds), 3))
    n = 0
    for h, (t0, t1, _) in enumerate(ctx.holds):
        if rng.random() > frac:
            continue
        u = unit_vec(rng) * th * rng.uniform(0.5, 1)
        ts = t0 + (t1 - t0) * rng.uniform(0.2, 0.8)
        dur = rng.uniform(0.1, 0.4)
        m = (ctx.t >= t0) & (ctx.t < t1)
        ctx.dtheta[m] += min_jerk((ctx.t[m] - ts) / dur)[:, None] * u[None]
        if h + 1 < len(ctx.holds):  # undo during the following move
            n0, n1 = t1, ctx.holds[h + 1][0]
            mm = (ctx.t >= n0) & (ctx.t < n1)
            ctx.dtheta[mm] += (1 - min_jerk((ctx.t[mm] - n0) / (n1 - n0)))[:, None] * u[None]
        else:
            ctx.dtheta[ctx.t >= t1] += u
        n += 1
    return dict(step_deg=round(th / DEG, 4), nudged_holds=n)


def motion_footsteps(ctx, rng, lvl):
    """Someone walks past: bursts of 3-10 s of floor-borne pulses at the step rate 1.5-2.5 Hz
    (each a 15-30 Hz damped pulse, mostly vertical), peak 1-50 mg, in 30-80 % of the holds."""
    A = logi(1, 50, lvl) * 1e-3 * G0
    frac = rng.uniform(0.3, 0.8)
    sr = rng.uniform(1.5, 2.5)
    f = rng.uniform(15, 30)
    w = 2 * np.pi * f
    n = 0
    for t0, t1, _ in ctx.holds:
        if rng.random() > frac:
            continue
        b0 = rng.uniform(t0, t1)
        b1 = min(t1, b0 + rng.uniform(3, 10))
        for tt in np.arange(b0, b1, 1 / sr):
            d = np.array([*(rng.normal(0, 0.2, 2)), 1.0])
            m = (ctx.t >= tt) & (ctx.t < tt + 0.3)
            x = ctx.t[m] - tt
            ctx.dp[m] += (-(A * rng.uniform(0.5, 1) / w ** 2) * np.exp(-0.15 * w * x) * np.sin(w * x))[:, None] * d[None]
        n += 1
    return dict(peak_mg=round(A / G0 * 1e3, 3), step_rate_hz=round(sr, 2), bursts=n)


# ================================================================== coloured noise
def cn_flicker(ctx, rng, lvl):
    """1/f (flicker) noise of the front end: one-sided PSD nd^2 fc / f on top of the white
    density nd of the part, 1/f corner fc 0.05-20 Hz, independent per axis."""
    fc = logi(0.05, 20, lvl)
    nd = ctx.unit["nd_g"]
    amp = lambda f: nd * np.sqrt(fc / f)
    ctx.noise += np.stack([shaped_noise(rng, len(ctx.t), ctx.fs, amp) for _ in range(3)], 1)
    return dict(corner_hz=round(fc, 4), white_ug_rthz=nd * 1e6)


def cn_gauss_markov(ctx, rng, lvl):
    """First-order Gauss-Markov offset wander: PSD 2 s^2 tau / (1 + (2 pi f tau)^2),
    sigma 0.03-3 mg, tau 0.5-60 s, independent per axis (sigma x 0.5-1)."""
    sig = logi(0.03, 3, lvl) * 1e-3
    tau = rng.uniform(0.5, 60)
    out = []
    for _ in range(3):
        s = sig * rng.uniform(0.5, 1)
        amp = lambda f, s=s: s * np.sqrt(4 * tau / (1 + (2 * np.pi * f * tau) ** 2))
        out.append(shaped_noise(rng, len(ctx.t), ctx.fs, amp))
    ctx.noise += np.stack(out, 1)
    return dict(sigma_mg=round(sig * 1e3, 4), tau_s=round(tau, 2))


def cn_random_walk(ctx, rng, lvl):
    """Offset random walk (integrated white noise, PSD K^2/(2 pi f)^2): K 2-200 ug/sqrt(s)
    per axis (x 0.5-1)."""
    K = logi(2, 200, lvl) * 1e-6
    w = rng.normal(size=(len(ctx.t), 3)) * K * rng.uniform(0.5, 1, 3)[None] / np.sqrt(ctx.fs)
    ctx.noise += np.cumsum(w, 0)
    return dict(k_ug_per_rts=round(K * 1e6, 3))


def cn_popcorn(ctx, rng, lvl):
    """Burst (popcorn, random telegraph) noise of a trap in the front end: the offset flips
    between +-A/2 with exponential dwell times of mean 0.5-20 s, A 0.05-3 mg, on 1-3 axes
    (Lorentzian spectrum)."""
    A = logi(0.05, 3, lvl) * 1e-3
    dwell = rng.uniform(0.5, 20)
    naxes = int(rng.integers(1, 4))
    axes = rng.choice(3, naxes, replace=False)
    T = ctx.t[-1]
    for ax in axes:
        flips = np.cumsum(rng.exponential(dwell, int(3 * T / dwell) + 10))
        state = (np.searchsorted(flips, ctx.t) + rng.integers(0, 2)) % 2
        ctx.noise[:, ax] += (state - 0.5) * A
    return dict(amp_mg=round(A * 1e3, 4), dwell_s=round(dwell, 2), axes=[int(a) for a in axes])


# ================================================================== out of catalogue
def ooc_clamp_pose(ctx, rng, lvl):
    """One bad pose: a clamp or a taut cable flexes the board in one hold only, and the package
    stress shifts the offset by 0.3-30 mg in a random direction for that hold."""
    h = int(rng.integers(1, len(ctx.holds)))
    vals = np.zeros((len(ctx.holds), 3))
    vals[h] = unit_vec(rng) * logi(0.3, 30, lvl) * 1e-3
    ctx.bias += hold_levels(ctx, vals)
    return dict(pose=h, shift_mg=round(float(np.linalg.norm(vals[h])) * 1e3, 4))


def ooc_motor_vibration(ctx, rng, lvl):
    """A motor or fan on the same bench shakes the body sinusoidally for the whole session:
    f 15 Hz .. 0.45 of the internal rate (aliases when above ODR/2), peak acceleration
    5-500 mg along a random direction, 30 % second harmonic, amplitude wandering 20 %."""
    f = rng.uniform(15, 0.45 * ctx.fs)
    A = logi(5, 500, lvl) * 1e-3 * G0
    d = unit_vec(rng)
    env = 1 + 0.2 * np.sin(2 * np.pi * ctx.t / rng.uniform(20, 200) + rng.uniform(0, 6.3))
    w = 2 * np.pi * f
    ph = rng.uniform(0, 2 * np.pi)
    x = -(A / w ** 2) * env * (np.sin(w * ctx.t + ph) + 0.3 / 4 * np.sin(2 * w * ctx.t + 2 * ph))
    ctx.dp += x[:, None] * d[None]
    return dict(freq_hz=round(f, 2), peak_mg=round(A / G0 * 1e3, 3))


def ooc_hysteresis(ctx, rng, lvl):
    """Mechanical hysteresis (stiction of the proof mass stop / spring plasticity): in each hold
    the offset of axis i is H_i sign(a_i(now) - a_i(previous hold)), H 0.1-5 mg (x 0.5-1 per axis);
    the offset changes during the move."""
    H = logi(0.1, 5, lvl) * rng.uniform(0.5, 1, 3) * 1e-3
    # gravity direction of each hold in the body frame (the sensor frame up to ~1 deg mounting)
    ups = np.array([ctx.poses[k][2, :] for _, _, k in ctx.holds])
    vals = np.zeros((len(ctx.holds), 3))
    for h in range(1, len(ctx.holds)):
        vals[h] = H * np.sign(ups[h] - ups[h - 1])
    vals[0] = vals[1] * 0  # the first hold is the reference
    ctx.bias += hold_levels(ctx, vals)
    return dict(h_mg=(H * 1e3).round(4).tolist())


def ooc_cross_bilinear(ctx, rng, lvl):
    """Cross-axis terms beyond linear (sense-electrode coupling that depends on the proof mass's
    position along another axis): a_i += c_i a_j a_k for the other two axes j,k,
    |c| 0.3-20 mg/g^2 per axis."""
    c = logi(0.3, 20, lvl) * rng.uniform(0.5, 1, 3) * rng.choice([-1, 1], 3) * 1e-3
    ctx.nonlin.append(lambda a, c=c: c[None] * np.stack([a[:, 1] * a[:, 2], a[:, 0] * a[:, 2], a[:, 0] * a[:, 1]], 1))
    return dict(c_mg_per_g2=(c * 1e3).round(4).tolist())


def ooc_offset_step(ctx, rng, lvl):
    """A sudden, lasting offset step (a brown-out re-loading trim registers, a drop shock
    moving the die): 0.3-20 mg in a random direction at a random time inside a hold in the
    middle of the session."""
    hs = ctx.holds[len(ctx.holds) // 3: max(len(ctx.holds) // 3 + 1, 2 * len(ctx.holds) // 3)]
    t0, t1, _ = hs[int(rng.integers(0, len(hs)))]
    ts = rng.uniform(t0 + 0.2 * (t1 - t0), t1 - 0.2 * (t1 - t0))
    d = unit_vec(rng) * logi(0.3, 20, lvl) * 1e-3
    ctx.bias[ctx.t >= ts] += d
    return dict(step_mg=round(float(np.linalg.norm(d)) * 1e3, 4), at_s=round(ts, 2))
