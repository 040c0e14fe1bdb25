"""Effect injectors: one function per physical effect.

Each takes the `Session` (see physics.py), a numpy Generator and a magnitude, writes
into the session's arrays and returns a dict of the parameters it drew (for the
manifest).  Units: specific force and offsets in g (magnitudes quoted in mg), time in s,
temperature in degC.  Magnitude ranges are taken from datasheet / literature figures
of consumer and industrial MEMS accelerometers, not from what any detector answers.
"""

import math

import numpy as np

from physics import bandnoise, loguniform, random_unit

MG = 1e-3  # g per mg


# ---------------------------------------------------------------- temperature profiles
def temp_profile(s, rng, kind, dT):
    """Temperature of the sensor die over the session, degC.

    kind:
      * "warmup": self-heating after power-on, T0 + dT (1 - exp(-t/tau)), tau 60-400 s
        (a PCB + package thermal time constant);
      * "updown": heated (hand, lamp, heat gun at a distance) then left to cool:
        a raised-cosine excursion of dT peaking at 35-65 % of the session;
      * "cycle": ambient cycling (climate control / chamber), sinusoid of amplitude dT/2,
        period 0.5-1.5 x session, on top of a small warm-up;
      * "ambient": the room, a 0.1-0.4 degC slow wobble (dT ignored).
    """
    t = s.t_true
    T0 = rng.uniform(18.0, 32.0)
    D = s.duration
    if kind == "warmup":
        tau = rng.uniform(60.0, 400.0)
        T = T0 + dT * (1 - np.exp(-t / tau))
    elif kind == "updown":
        c = rng.uniform(0.35, 0.65) * D
        w = rng.uniform(0.5, 0.8) * D
        x = np.clip((t - c) / w, -0.5, 0.5)
        T = T0 + dT * 0.5 * (1 + np.cos(2 * math.pi * x))
    elif kind == "cycle":
        per = rng.uniform(0.5, 1.5) * D
        T = T0 + 0.5 * dT * np.sin(2 * math.pi * t / per + rng.uniform(0, 2 * math.pi)) \
            + 0.1 * dT * (1 - np.exp(-t / 120.0))
    else:
        T = T0 + rng.uniform(0.1, 0.4) * np.sin(2 * math.pi * t / rng.uniform(300, 1200) + rng.uniform(0, 6.3))
    return T, dict(temp_profile=kind, T0=round(T0, 2), dT=round(float(dT), 2))


def thermal_lag(s, T, tau):
    """First-order lag: the MEMS element follows the logged (board) temperature through a
    thermal resistance-capacitance with time constant tau seconds."""
    a = math.exp(-1 / (s.fs * tau))
    return ar1((1 - a) * np.asarray(T, float), a, T[0])


def ar1(w, phi, x0):
    """x[n] = phi x[n-1] + w[n], x[-1] = x0 (a scalar loop over Python floats)."""
    out = []
    acc = float(x0)
    for v in w.tolist():
        acc = phi * acc + v
        out.append(acc)
    return np.array(out)


def temperature_bias(s, rng, T_die, tc_mg_per_c):
    """Zero-g offset temperature coefficient: bias_i(t) = tc_i (T_die(t) - T_die(0)), tc a
    random vector of norm tc_mg_per_c mg/degC (datasheets: 0.15-1 mg/degC)."""
    tc = random_unit(rng) * tc_mg_per_c * MG
    s.bias += np.outer(T_die - T_die[0], tc)
    return dict(tc_bias_mg_per_c=np.round(tc / MG, 4).tolist())


def temperature_scale(s, rng, T_die, tc_pct_per_c):
    """Sensitivity temperature coefficient: scale_i(t) = tc_i (T_die - T_die(0)), each axis
    with its own sign, norm tc_pct_per_c %/degC (datasheets: 0.01-0.03 %/degC)."""
    tc = random_unit(rng) * tc_pct_per_c * 1e-2
    s.scale += np.outer(T_die - T_die[0], tc)
    return dict(tc_scale_pct_per_c=np.round(tc * 100, 5).tolist())


# ---------------------------------------------------------------- drift (no temperature)
def drift_warmup(s, rng, amp_mg):
    """Warm-up drift of the zero-g offset after power-on (self-heating, charge settling
    of the MEMS electrodes) with no temperature column logged:
    b(t) = a (1 - exp(-t/tau)), |a| = amp_mg, tau 0.15-0.6 x session length."""
    tau = rng.uniform(0.15, 0.6) * s.duration
    a = random_unit(rng) * amp_mg * MG
    s.bias += np.outer(1 - np.exp(-s.t_true / tau), a)
    return dict(tau_s=round(tau, 1), vec_mg=np.round(a / MG, 3).tolist())


def drift_wander(s, rng, amp_mg):
    """Slow random wander of the zero-g offset: a Brownian path low-passed (4th order in
    the spectrum) to frequencies below ~3/session, i.e. nearly constant within one hold
    but different from pose to pose.  Scaled to an rms (over the session) of amp_mg per
    axis."""
    N = s.N
    f = np.fft.rfftfreq(N, 1 / s.fs)
    fc = 3.0 / s.duration
    out = np.zeros((N, 3))
    for i in range(3):
        w = np.fft.rfft(rng.normal(size=N))
        with np.errstate(divide="ignore"):
            h = 1.0 / (1j * 2 * math.pi * np.maximum(f, f[1]))  # integrate: random walk
        h /= (1 + (f / fc) ** 4)
        x = np.fft.irfft(w * h, N)
        x -= x[0]
        out[:, i] = x / x.std() * amp_mg * MG
    s.bias += out
    return dict(corner_hz=round(fc, 5))


def drift_ramp(s, rng, amp_mg):
    """Linear offset ramp over the session (unlogged ambient change, aging of a freshly
    soldered part relaxing): b(t) = a t / T_session, |a| = amp_mg."""
    a = random_unit(rng) * amp_mg * MG
    s.bias += np.outer(s.t_true / s.duration, a)
    return dict(vec_mg=np.round(a / MG, 3).tolist())


# ---------------------------------------------------------------- scale non-linearity
def nonlin_poly(s, rng, amp_mg, even, odd):
    """Non-linear transfer of each sensing axis: y_i = f_i + k2_i f_i^2 + k3_i f_i^3 (f in g).
    amp_mg is the size of the non-linear term at |f| = 1 g (|k| in mg/g^2 or mg/g^3), per
    axis with random signs and 0.5-1x spread (datasheets: 0.1-0.5 %FS at +-2 g, i.e. up
    to ~10 mg)."""
    k2 = (rng.uniform(0.5, 1, 3) * rng.choice([-1, 1], 3) * amp_mg * MG) if even else np.zeros(3)
    k3 = (rng.uniform(0.5, 1, 3) * rng.choice([-1, 1], 3) * amp_mg * MG) if odd else np.zeros(3)
    s.nl.append(lambda f, k2=k2, k3=k3: k2 * f ** 2 + k3 * f ** 3)
    return dict(k2_mg=np.round(k2 / MG, 3).tolist(), k3_mg=np.round(k3 / MG, 3).tolist())


def nonlin_saturation(s, rng, amp_mg):
    """Soft compression of the sensing element towards its electrostatic/mechanical limit:
    y = fsat tanh(f / fsat) per axis, fsat chosen so the loss at 1 g is amp_mg (an odd
    non-linearity, mostly cubic)."""
    # tanh(x)/x ~ 1 - x^2/3  ->  loss at 1 g ~ 1/(3 fsat^2)
    fsat = math.sqrt(1.0 / (3 * amp_mg * MG))
    s.nl.append(lambda f, fsat=fsat: fsat * np.tanh(f / fsat) - f)
    return dict(fsat_g=round(fsat, 3))


# ---------------------------------------------------------------- settling after placement
def settling_exponential(s, rng, amp_mg):
    """Offset transient after each placement: the package/adhesive stress from the hand's
    grip and the impact relaxes, b(t) = a_k exp(-(t - t_k)/tau) from each hold start t_k.
    a_k random direction, |a_k| = amp_mg x U(0.5, 1.5); tau 0.3-3 s (one per session,
    +-30 % per pose)."""
    tau = loguniform(rng, 0.3, 3.0)
    for (a, b) in s.holds:
        n = s.N - a
        tt = np.arange(n) / s.fs
        tk = tau * rng.uniform(0.7, 1.3)
        v = random_unit(rng) * amp_mg * MG * rng.uniform(0.5, 1.5)
        s.bias[a:] += np.outer(np.exp(-tt / tk), v)
    return dict(tau_s=round(tau, 3))


def settling_ringing(s, rng, amp_mg):
    """Damped ringing of the mount after each placement (the board on its stand-offs or a
    fixture on a compliant table): a linear acceleration a_k e^{-zeta w t} sin(w_d t)
    along a random direction, natural frequency 3-25 Hz (kept below 0.4 fs), damping
    ratio 0.02-0.15, initial amplitude amp_mg x U(0.5, 1.5)."""
    fn = min(loguniform(rng, 3.0, 25.0), 0.4 * s.fs)
    zeta = loguniform(rng, 0.02, 0.15)
    w = 2 * math.pi * fn
    wd = w * math.sqrt(1 - zeta ** 2)
    for (a, b) in s.holds:
        n = b - a
        tt = np.arange(n) / s.fs
        v = random_unit(rng) * amp_mg * MG * rng.uniform(0.5, 1.5)
        s.f[a:b] += np.outer(np.exp(-zeta * w * tt) * np.sin(wd * tt + rng.uniform(0, 0.5)), v)
    return dict(fn_hz=round(fn, 2), zeta=round(zeta, 3))


# ---------------------------------------------------------------- motion during holds
def motion_taps(s, rng, amp_mg):
    """Taps / knocks on the table during holds: Poisson events (0.03-0.3 per s of hold, at
    least one per session) at uniform times within the holds, each a half-sine
    acceleration pulse 5-30 ms long, peak amp_mg x U(0.3, 1.5), random direction, followed
    by mount ringing (20-60 Hz, capped at 0.4 fs, 0.3 x the peak, decay 30-100 ms)."""
    rate = loguniform(rng, 0.03, 0.3)
    lens = np.array([b - a for a, b in s.holds])
    total = lens.sum() / s.fs
    k = max(1, int(rng.poisson(rate * total)))
    for _ in range(k):
        h = int(rng.choice(len(lens), p=lens / lens.sum()))
        a, b = s.holds[h]
        i0 = a + int(rng.integers(0, b - a))
        width = rng.uniform(0.005, 0.03)
        nw = int(math.ceil(width * s.fs))
        pk = amp_mg * MG * rng.uniform(0.3, 1.5)
        v = random_unit(rng)
        n_ring = int(0.4 * s.fs)
        dt = 1 / s.fs
        tt = np.arange(nw + 1 + n_ring) * dt - rng.uniform(0, dt)  # pulse starts between samples
        # each sample is the mean of the half-sine over its interval (the sensor's
        # anti-alias filter integrates), so pulses shorter than dt are not lost
        t1 = np.clip(tt, 0, width)
        t2 = np.clip(tt + dt, 0, width)
        pulse = width / np.pi * (np.cos(np.pi * t1 / width) - np.cos(np.pi * t2 / width)) / dt
        fr = min(rng.uniform(20, 60), 0.4 * s.fs)
        ring = np.where(tt >= width, 0.3 * np.exp(-(tt - width) / rng.uniform(0.03, 0.1))
                        * np.sin(2 * math.pi * fr * (tt - width)), 0.0)
        seg = (pulse + ring) * pk
        e = min(b, i0 + len(seg))
        s.f[i0:e] += np.outer(seg[: e - i0], v)
    return dict(rate_per_s=round(rate, 3), taps=k)


def rotate_small(vecs, axis, ang):
    """Rotate rows of vecs about the unit axis by small angles ang (array, rad), Rodrigues."""
    c, sn = np.cos(ang)[:, None], np.sin(ang)[:, None]
    k = axis[None, :]
    return vecs * c + np.cross(k, vecs) * sn + k * (vecs @ axis)[:, None] * (1 - c)


def motion_sway(s, rng, tilt_deg):
    """Sway of the support during holds (device on a flexible arm or a desk that rocks):
    the device tilts by theta(t) about a random axis, narrow-band around f0 = 0.5-5 Hz,
    rms tilt_deg x U(0.5, 1.5) per hold (a rocking desk or arm: 0.01-0.5 deg), at a lever
    arm r = 5-30 cm from the pivot.  Sensed: gravity rotated by theta, plus tangential
    acceleration r theta'' and centripetal r theta'^2.  60-100 % of holds sway."""
    f0 = loguniform(rng, 0.5, 5.0)
    r = rng.uniform(0.05, 0.30)
    th_rms = math.radians(tilt_deg)
    frac = rng.uniform(0.6, 1.0)
    for (a, b) in s.holds:
        if rng.random() > frac:
            continue
        n = b - a
        axis = random_unit(rng)
        th = bandnoise(rng, n + 2, s.fs, f0 * 0.8, f0 * 1.25, th_rms * rng.uniform(0.5, 1.5))
        thd = np.gradient(th) * s.fs
        thdd = np.gradient(thd) * s.fs
        th, thd, thdd = th[1:-1], thd[1:-1], thdd[1:-1]
        g = rotate_small(s.f[a:b], axis, th)
        tang_dir = np.cross(axis, random_unit(rng))
        tang_dir /= np.linalg.norm(tang_dir)
        rad_dir = np.cross(axis, tang_dir)
        s.f[a:b] = g + np.outer(r * thdd / 9.80665, tang_dir) + np.outer(r * thd ** 2 / 9.80665, rad_dir)
    tang_mg = 1e3 * r * th_rms * (2 * math.pi * f0) ** 2 / 9.80665
    return dict(f0_hz=round(f0, 3), lever_m=round(r, 3), tangential_rms_mg=round(tang_mg, 4))


def motion_tremor(s, rng, amp_mg):
    """The device held by hand during holds: physiological tremor (narrow band 8-12 Hz,
    capped at 0.45 fs) of amp_mg rms per axis, hand drift (0.2-2 Hz, 0.5-1.5 x amp_mg)
    and the matching small tilt of the hand (0.1-0.5 deg rms, 0.1-1 Hz) rotating gravity.
    Literature: postural hand tremor 5-50 mg rms."""
    tilt = math.radians(rng.uniform(0.1, 0.5))
    for (a, b) in s.holds:
        n = b - a
        tr = np.stack([bandnoise(rng, n, s.fs, 8, min(12, 0.45 * s.fs), amp_mg * MG) for _ in range(3)], 1)
        dr = np.stack([bandnoise(rng, n, s.fs, 0.2, 2, amp_mg * MG * rng.uniform(0.5, 1.5)) for _ in range(3)], 1)
        ang = bandnoise(rng, n, s.fs, 0.1, 1.0, tilt)
        s.f[a:b] = rotate_small(s.f[a:b], random_unit(rng), ang) + tr + dr
    return dict(tilt_rms_deg=round(math.degrees(tilt), 3))


# ---------------------------------------------------------------- coloured noise
def colored_random_walk(s, rng, k_ug):
    """Offset random walk (accelerometer 'rate random walk'): b(t) = K W(t), K in ug/sqrt(s)
    (Allan deviation rising as K sqrt(tau/3); consumer MEMS ~ 2-100 ug/sqrt(s))."""
    step = k_ug * 1e-6 * math.sqrt(1 / s.fs)
    s.noise += np.cumsum(rng.normal(0, step, (s.N, 3)), axis=0)
    return {}


def colored_flicker(s, rng, b_ug):
    """Flicker (1/f) noise: two-sided PSD B^2 / (2 pi f) as in IEEE 952 (one-sided
    B^2 / (pi f)), whose Allan deviation plateau is sqrt(2 ln 2 / pi) B = 0.664 B (bias
    instability B), synthesised by FFT shaping of white noise; consumer MEMS B ~ 20-500 ug."""
    N = s.N
    f = np.fft.rfftfreq(N, 1 / s.fs)
    f[0] = f[1]
    S = (b_ug * 1e-6) ** 2 / (math.pi * f)  # one-sided
    h = np.sqrt(S * s.fs / 2)
    for i in range(3):
        w = np.fft.rfft(rng.normal(size=N))
        w[0] = 0
        s.noise[:, i] += np.fft.irfft(w * h, N)
    return {}


def colored_gauss_markov(s, rng, sigma_ug):
    """First-order Gauss-Markov offset noise (correlated, e.g. thermo-mechanical noise of
    the package or electronics 1/f corner): stationary std sigma_ug, correlation time tau
    0.5-30 s: x[n+1] = phi x[n] + sigma sqrt(1 - phi^2) w[n]."""
    tau = loguniform(rng, 0.5, 30.0)
    phi = math.exp(-1 / (s.fs * tau))
    sig = sigma_ug * 1e-6
    w = rng.normal(0, sig * math.sqrt(1 - phi ** 2), (s.N, 3))
    x0 = rng.normal(0, sig, 3)
    s.noise += np.stack([ar1(w[:, i], phi, x0[i]) for i in range(3)], 1)
    return dict(tau_s=round(tau, 3))


# ---------------------------------------------------------------- out of catalogue
def ooc_bad_pose(s, rng, amp_mg):
    """One bad pose: during one hold the whole setup sits in an accelerating frame (a lift,
    a vehicle, the table pushed): a sustained linear acceleration of amp_mg with smooth
    0.3-1 s ramps, lasting 40-90 % of that hold, random direction."""
    k = int(rng.integers(len(s.holds)))
    a, b = s.holds[k]
    n = b - a
    L = int(n * rng.uniform(0.4, 0.9))
    i0 = a + int(rng.integers(0, n - L + 1))
    ramp = max(1, int(rng.uniform(0.3, 1.0) * s.fs))
    prof = np.ones(L)
    r = np.sin(np.linspace(0, np.pi / 2, min(ramp, L // 2))) ** 2
    prof[: len(r)] = r
    prof[L - len(r):] = r[::-1]
    s.f[i0:i0 + L] += np.outer(prof, random_unit(rng) * amp_mg * MG)
    return dict(pose=k)


def ooc_mains(s, rng, amp_mg):
    """Mains pick-up: 50 or 60 Hz (+-0.05 Hz) and its 3rd harmonic (0.2-0.5 x) coupled into
    the analogue front end, amp_mg peak per axis (random phases/weights).  Sampled
    without anti-alias filtering, so it aliases; rates are chosen so the alias of the
    fundamental lies above 1 Hz (a beat near DC would be indistinguishable from drift)."""
    def alias_of(f):
        return abs(f - s.fs * round(f / s.fs))
    grids = [g for g in (50.0, 60.0) if min(alias_of(g - 0.05), alias_of(g + 0.05)) > 1.0] or [60.0]
    fm = float(rng.choice(grids)) + rng.uniform(-0.05, 0.05)
    alias = alias_of(fm)
    h3 = rng.uniform(0.2, 0.5)
    w = random_unit(rng)
    for i in range(3):
        ph = rng.uniform(0, 2 * math.pi, 2)
        s.noise[:, i] += amp_mg * MG * w[i] * (np.sin(2 * math.pi * fm * s.t_true + ph[0])
                                               + h3 * np.sin(2 * math.pi * 3 * fm * s.t_true + ph[1]))
    return dict(mains_hz=round(fm, 3), alias_hz=round(alias, 3), h3=round(h3, 3))


def ooc_hysteresis(s, rng, amp_mg):
    """Hysteresis by rotation direction: after each turn the offset takes +h or -h (h a
    random vector, |h| = amp_mg) according to the sense of the rotation about a body axis
    (sign of (u_prev x u_cur) . e), as from a mechanically hysteretic mount or a proof
    mass that sticks on one side; the first pose has zero offset."""
    e = random_unit(rng)
    h = random_unit(rng) * amp_mg * MG
    for k in range(1, len(s.holds)):
        sg = np.sign(np.dot(np.cross(s.u[k - 1], s.u[k]), e)) or 1.0
        start = s.holds[k - 1][1]
        end = s.holds[k][1] if k + 1 < len(s.holds) else s.N
        s.bias[start:end] += sg * h
    return dict(axis=np.round(e, 3).tolist())


def ooc_cross_axis(s, rng, amp_mg):
    """Cross-axis coupling beyond the linear model: bilinear terms
    y_x += c_x f_y f_z, y_y += c_y f_z f_x, y_z += c_z f_x f_y (mg/g^2), e.g. from proof-mass
    rotation in a coupled-axis MEMS; amp_mg = max |c|."""
    c = rng.uniform(0.5, 1.0, 3) * rng.choice([-1, 1], 3) * amp_mg * MG
    s.nl.append(lambda f, c=c: np.stack([c[0] * f[:, 1] * f[:, 2], c[1] * f[:, 2] * f[:, 0],
                                         c[2] * f[:, 0] * f[:, 1]], 1))
    return dict(c_mg=np.round(c / MG, 3).tolist())


def ooc_g_step(s, rng, amp_mg):
    """g-sensitive offset step: when one sensing axis points down (its specific force
    below -0.2 g) a loose part / cracked solder joint shifts the offset by a fixed vector
    of amp_mg (a step in orientation, not a smooth polynomial)."""
    ax = int(rng.integers(3))
    v = random_unit(rng) * amp_mg * MG
    down = s.f[:, ax] < -0.2
    s.bias[down] += v
    return dict(axis=int(ax))


def ooc_single_step(s, rng, amp_mg):
    """A single offset step at one random time during the session (a knock, an ESD event,
    a register reload): b = a for t > t_s, |a| = amp_mg; t_s in the middle 20-80 %."""
    i = int(rng.uniform(0.2, 0.8) * s.N)
    v = random_unit(rng) * amp_mg * MG
    s.bias[i:] += v
    return dict(t_step_s=round(i / s.fs, 2))
