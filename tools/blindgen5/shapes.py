"""blindgen5 shapes.  Each shape: fn(rng, L) -> (magnitude, unit, params); it configures the Log L
(session, part, trajectory perturbations, reading effects, temperature column)."""
import numpy as np

from sim import (G0, Thermometer, coarse_grid, lag1, loguni, onset_env, smooth5, unit)


# ------------------------------------------------------------------------------------------ helpers
def _hold_mask(ctx):
    return ctx['hold'] >= 0


def normalise(shape, M_mg, mode):
    """Wrap an effect shape so its size over the holds equals M_mg.
    mode: 'change' (peak |d(t) - d(start)|), 'peak' (peak |d|), 'std' (largest per-axis std)."""
    def eff(ctx):
        d = shape(ctx)
        m = _hold_mask(ctx)
        if mode == 'change':
            s = np.max(np.linalg.norm(d[m] - d[0], axis=1))
        elif mode == 'peak':
            s = np.max(np.linalg.norm(d[m], axis=1))
        else:
            s = np.max(np.std(d, axis=0))
        return d * (M_mg * 1e-3 / s) if s > 0 else d
    return eff


def maybe_flat_temp(rng, L, p):
    if rng.uniform() < p:
        L.flat_temp()


def signs(rng, n=3):
    return rng.choice([-1.0, 1.0], n)


def fade_after_hold(S, k, t):
    """1 during hold k, C2 fade to 0 over the following move."""
    out = np.ones_like(t)
    last = k >= S.n - 1
    kk = np.minimum(k, S.n - 2) if S.n > 1 else k
    if S.n > 1:
        u = (t - S.he[k]) / S.moves[kk]
        out = np.where(last, 1.0, 1.0 - smooth5(u))
    return out


def horiz_axis(rng):
    a = rng.uniform(0, 2 * np.pi)
    return np.array([np.cos(a), np.sin(a), 0.0])


def coarse_interp(t, tc, xc):
    return np.stack([np.interp(t, tc, xc[:, j]) for j in range(xc.shape[1])], 1)


# ============================================================================================ clean
def clean_standard(rng, L):
    L.session()
    P = L.make_part()
    maybe_flat_temp(rng, L, 0.2)
    return 0.0, 'none', dict(noise_density_ug=P.nd)


def clean_coarse_quant(rng, L):
    L.session()
    P = L.make_part(nd=loguni(rng, 50, 120), min_lsb_mg=1.9, max_lsb_mg=8.0, fs_max=208, fir='none')
    sig = P.nd * 1e-3 * np.sqrt(P.fs / 2)
    return 0.0, 'none', dict(noise_density_ug=P.nd, lsb_mg=1000 / P.lsb_per_g, noise_sigma_mg=sig)


def clean_lowpass(rng, L):
    L.session()
    P = L.make_part(fir=rng.choice(['boxcar', 'sinc']), fs_min=200)
    return 0.0, 'none', dict(noise_density_ug=P.nd, fir=P.fir_kind, fir_param=float(P.fir_param))


def clean_jitter(rng, L):
    L.session()
    P = L.make_part(jitter=True)
    P.jit_frac = rng.uniform(0.2, 0.45)
    return 0.0, 'none', dict(noise_density_ug=P.nd, jitter_frac=P.jit_frac, clock_ppm=P.clock_ppm)


def clean_short_holds(rng, L):
    L.session(n_poses=int(rng.integers(20, 41)), mode=rng.choice(['uniform', 'spread']),
              hold_range=(2.0, 4.0), move_range=(1.0, 2.5))
    P = L.make_part()
    return 0.0, 'none', dict(noise_density_ug=P.nd)


def clean_long_holds(rng, L):
    L.session(n_poses=int(rng.integers(12, 17)), hold_range=(20.0, 30.0))
    P = L.make_part()
    maybe_flat_temp(rng, L, 0.3)
    return 0.0, 'none', dict(noise_density_ug=P.nd)


def clean_jig_temp(rng, L):
    L.session(mode='jig')
    P = L.make_part()
    L.flat_temp()
    return 0.0, 'none', dict(noise_density_ug=P.nd)


def clean_noisy_fast(rng, L):
    L.session(n_poses=int(rng.integers(12, 17)), hold_range=(3.0, 10.0))
    P = L.make_part(nd=loguni(rng, 250, 400), fs_min=400)
    return 0.0, 'none', dict(noise_density_ug=P.nd)


# ============================================================================================ drift
def _drift_common(rng, L):
    S = L.session()
    L.make_part()
    maybe_flat_temp(rng, L, 0.3)
    return S, S.duration


def drift_warmup(rng, L):
    S, D = _drift_common(rng, L)
    two = bool(rng.uniform() < 0.5)
    tau1 = D * loguni(rng, 0.03, 0.5)
    tau2 = D * loguni(rng, 0.5, 3.0)
    v1 = unit(rng)
    v2 = unit(rng) * rng.uniform(0.3, 1.0) if two else np.zeros(3)
    M = loguni(rng, 0.1, 15.0)

    def shape(ctx):
        t = ctx['t']
        return np.outer(1 - np.exp(-t / tau1), v1) + np.outer(1 - np.exp(-t / tau2), v2)
    L.effects.append(normalise(shape, M, 'change'))
    return M, 'mg change', dict(tau1_s=tau1, tau2_s=tau2 if two else 0.0, two_constants=two,
                                dir1=v1, dir2=v2)


def drift_ageing_poly(rng, L):
    S, D = _drift_common(rng, L)
    v1 = unit(rng)
    quad = bool(rng.uniform() < 0.5)
    v2 = unit(rng) * rng.uniform(0.5, 2.0) if quad else np.zeros(3)
    M = loguni(rng, 0.1, 15.0)

    def shape(ctx):
        x = ctx['t'] / D
        return np.outer(x, v1) + np.outer(x * x, v2)
    L.effects.append(normalise(shape, M, 'change'))
    return M, 'mg change', dict(linear_dir=v1, quad_vec=v2, quadratic=quad)


def drift_wander(rng, L):
    S, D = _drift_common(rng, L)
    K = int(rng.integers(3, 7))
    fr = rng.uniform(0.2, 2.5, K) / D          # at most a few cycles per session
    ph = rng.uniform(0, 2 * np.pi, (K, 3))
    amp = rng.normal(size=(K, 3)) / np.sqrt(fr * D)[:, None]
    M = loguni(rng, 0.1, 12.0)

    def shape(ctx):
        t = ctx['t']
        return sum(np.sin(2 * np.pi * fr[i] * t[:, None] + ph[i]) * amp[i] for i in range(K))
    L.effects.append(normalise(shape, M, 'change'))
    return M, 'mg change', dict(freqs_hz=fr, n_components=K)


def drift_log_creep(rng, L):
    S, D = _drift_common(rng, L)
    tau = loguni(rng, 1.0, 100.0)
    v = unit(rng)
    M = loguni(rng, 0.1, 12.0)

    def shape(ctx):
        return np.outer(np.log1p(ctx['t'] / tau), v)
    L.effects.append(normalise(shape, M, 'change'))
    return M, 'mg change', dict(tau_s=tau, dir=v)


def drift_supply_sag(rng, L):
    """Battery discharge: supply falls linearly with a knee; ratiometric bias and scale follow it."""
    S, D = _drift_common(rng, L)
    rate = rng.uniform(0.2, 1.0)
    knee = rng.uniform(0.0, 1.0)
    tk = D * rng.uniform(0.5, 1.2)
    cb = unit(rng)
    cs = rng.normal(size=3) * rng.uniform(0.0, 1.5)   # scale part (per g of input)
    M = loguni(rng, 0.1, 12.0)

    def shape(ctx):
        t = ctx['t']
        dv = -(rate * t / D + knee * np.expm1(np.maximum(t - tk, 0.0) / (0.15 * D)) * 0.1)
        return np.outer(dv, cb) + dv[:, None] * cs * ctx['Af']
    L.effects.append(normalise(shape, M, 'change'))
    return M, 'mg change', dict(lin_rate=rate, knee=knee, knee_time_s=tk, bias_dir=cb, scale_coef=cs)


def drift_scale(rng, L):
    """Scale factors creep with time (gain warm-up / reference settling), no temperature cause."""
    S, D = _drift_common(rng, L)
    k = rng.normal(size=3)
    tau = D * loguni(rng, 0.05, 2.0)
    M = loguni(rng, 150.0, 15000.0)  # ppm

    def shape(ctx):
        s = (1 - np.exp(-ctx['t'] / tau))[:, None] * k / np.max(np.abs(k)) * M * 1e-6
        return s * ctx['Af']
    L.effects.append(shape)
    return M, 'ppm scale change', dict(tau_s=tau, axis_weights=k / np.max(np.abs(k)))


# ====================================================================================== temperature
def _temp_profile(rng, kind, D, tc):
    T0 = rng.uniform(18.0, 30.0)
    info = dict(profile=kind)
    if kind == 'warmup':
        dT = loguni(rng, 1.5, 25.0)
        tau = D * loguni(rng, 0.1, 1.0)
        T = T0 + dT * (1 - np.exp(-tc / tau))
        info.update(dT=dT, tau_s=tau)
    elif kind == 'cooling':
        dT = loguni(rng, 2.0, 30.0)
        tau = D * loguni(rng, 0.1, 1.0)
        T = T0 + dT * np.exp(-tc / tau)
        info.update(dT=dT, tau_s=tau)
    elif kind == 'room_cycle':
        Pd = D * rng.uniform(0.4, 2.0)
        A = loguni(rng, 0.4, 3.0)
        ph = rng.uniform(0, 2 * np.pi)
        tr = rng.uniform(-0.5, 0.5)
        x = 2 * np.pi * tc / Pd + ph
        T = T0 + A * (np.sin(x) + 0.25 * np.sin(2 * x + 1.0)) + tr * tc / D
        info.update(period_s=Pd, amp=A, trend=tr)
    elif kind == 'self_heating':
        d1, t1 = loguni(rng, 0.5, 5.0), rng.uniform(10.0, 60.0)
        d2, t2 = loguni(rng, 0.5, 6.0), rng.uniform(150.0, 1200.0)
        T = T0 + d1 * (1 - np.exp(-tc / t1)) + d2 * (1 - np.exp(-tc / t2))
        info.update(dT1=d1, tau1_s=t1, dT2=d2, tau2_s=t2)
    else:  # chamber ramp / soak
        rate = rng.uniform(0.5, 3.0) / 60.0 * rng.choice([-1, 1])  # C/s
        ts = D * rng.uniform(0.05, 0.3)
        te = min(D * rng.uniform(0.6, 0.95), ts + 40.0 / abs(rate))
        T = T0 + rate * (np.clip(tc, ts, te) - ts)
        info.update(rate_C_per_min=rate * 60, start_s=ts, end_s=te)
    return T, info


def _temperature(kind):
    def fn(rng, L):
        S = L.session()
        L.make_part()
        D = S.duration
        tc = coarse_grid(D)
        dt = tc[1] - tc[0]
        Tenv, info = _temp_profile(rng, kind, D, tc)
        if kind == 'self_heating':
            Tdie = Tenv  # heat source is the die itself
        else:
            Tdie = lag1(Tenv, dt, loguni(rng, 2.0, 60.0))
        th = Thermometer(rng)
        expose = 'die' if (kind == 'self_heating' or rng.uniform() < 0.5) else 'environment'
        Texp = Tdie if expose == 'die' else Tenv
        c1 = rng.normal(size=3)
        quad = bool(rng.uniform() < 0.4)
        scale = bool(rng.uniform() < 0.4)
        c2 = rng.normal(size=3) * 0.05 if quad else np.zeros(3)
        ks = rng.normal(size=3) * rng.uniform(0.2, 1.0) if scale else np.zeros(3)
        Tref = 25.0
        span = float(np.ptp(Tdie))
        M = loguni(rng, 0.1, 15.0)
        # keep the temperature coefficient physical (<= ~2.5 mg/C over the die's span)
        M = min(M, 2.5 * max(span, 0.05))

        def temp_fn(ctx):
            ctx['T_die'] = np.interp(ctx['t'], tc, Tdie)
            return th.column(rng, ctx['t'], tc, Texp)

        def shape(ctx):
            dT = ctx['T_die'] - Tref
            return np.outer(dT, c1) + np.outer(dT * dT, c2) + (dT[:, None] * ks) * ctx['Af']

        eff = normalise(shape, M, 'change')
        L.temp_fn = temp_fn
        L.temp_dec = th.dec
        L.effects.append(eff)
        info.update(th.info())
        info.update(die_span_C=span, thermometer_sees=expose, quadratic=quad, scale_tc=scale,
                    bias_tc_shape=c1, quad_shape=c2, scale_tc_shape=ks, T_ref=Tref)
        L.extra['temp_model'] = info
        return M, 'mg change', info
    return fn


# =============================================================================== scale-nonlinearity
def _nl(kind):
    def fn(rng, L):
        L.session()
        L.make_part()
        maybe_flat_temp(rng, L, 0.15)
        M = loguni(rng, 0.1, 15.0)   # mg deviation at 1 g on the worst axis
        m = M * 1e-3
        p = dict(kind=kind)
        if kind in ('quadratic', 'cubic', 'mixed', 'single_axis', 'odd_abs'):
            k2 = np.zeros(3)
            k3 = np.zeros(3)
            if kind == 'quadratic':
                k2 = rng.normal(size=3)
            elif kind == 'cubic':
                k3 = rng.normal(size=3)
            elif kind == 'mixed':
                k2 = rng.normal(size=3)
                k3 = rng.normal(size=3)
            elif kind == 'single_axis':
                ax = int(rng.integers(3))
                k2[ax] = rng.normal()
                k3[ax] = rng.normal() * rng.uniform(0, 1)
                p['axis'] = ax
            if kind == 'odd_abs':
                ka = rng.normal(size=3)
                ka *= m / np.max(np.abs(ka))
                p['k_abs_g_per_g2'] = ka

                def eff(ctx):
                    x = ctx['Af']
                    return ka * x * np.abs(x)
            else:
                s = np.max(np.abs(k2) + np.abs(k3))
                k2 *= m / s
                k3 *= m / s
                p.update(k2_per_g=k2, k3_per_g2=k3)

                def eff(ctx):
                    x = ctx['Af']
                    return k2 * x * x + k3 * x * x * x
        else:  # soft saturation / compression knee near full scale
            n = rng.uniform(2.5, 8.0)
            comp = m * rng.uniform(0.3, 1.0, 3)
            comp[rng.integers(3)] = m
            Sk = ((1 - comp) ** (-n) - 1) ** (-1.0 / n)   # knee such that 1 g is compressed by comp
            p.update(knee_g=Sk, sharpness=n, compression_at_1g_g=comp)

            def eff(ctx):
                x = ctx['Af']
                return x / (1 + (np.abs(x) / Sk) ** n) ** (1.0 / n) - x
        L.effects.append(eff)
        return M, 'mg at 1 g', p
    return fn


# ========================================================================================= settling
def _settle_common(rng, L):
    S = L.session()
    L.make_part()
    return S


def settle_exp_offset(rng, L):
    S = _settle_common(rng, L)
    tau = loguni(rng, 0.4, min(10.0, 0.8 * np.mean(S.holds) + 0.5))
    u = unit(rng)
    dk = u + 0.35 * rng.normal(size=(S.n, 3))
    dk *= rng.uniform(0.6, 1.4, (S.n, 1)) * rng.choice([-1.0, 1.0])
    M = loguni(rng, 0.2, 25.0)

    def shape(ctx):
        k, tau_s = S.last_landing(ctx['t'])
        return dk[k] * np.exp(-tau_s / tau)[:, None]
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg at set-down', dict(tau_s=tau, mean_dir=u)


def settle_two_stage(rng, L):
    S = _settle_common(rng, L)
    t1 = loguni(rng, 0.2, 1.5)
    t2 = loguni(rng, 3.0, min(25.0, max(4.0, np.mean(S.holds))))
    a = rng.uniform(0.2, 0.8)
    u = unit(rng)
    dk = u + 0.2 * rng.normal(size=(S.n, 3))
    M = loguni(rng, 0.2, 25.0)

    def shape(ctx):
        k, tau_s = S.last_landing(ctx['t'])
        return dk[k] * (a * np.exp(-tau_s / t1) + (1 - a) * np.exp(-tau_s / t2))[:, None]
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg at set-down', dict(tau_fast_s=t1, tau_slow_s=t2, fast_fraction=a, dir=u)


def settle_thermal_touch(rng, L):
    """Hand warmth: die heated while handled (moves), cools after each set-down."""
    S = _settle_common(rng, L)
    D = S.duration
    tau_c = loguni(rng, 1.5, max(2.0, 0.6 * np.mean(S.holds)))
    tc = coarse_grid(D, 0.05)
    k, mv = S.seg(tc)
    heat = mv.astype(float)
    dt = tc[1] - tc[0]
    th = np.empty(len(tc))
    x = rng.uniform(0.5, 1.5) * np.mean(S.moves)   # warm from being placed at t = 0
    a = np.exp(-dt / tau_c)
    for i in range(len(tc)):
        x = x * a + heat[i] * dt
        th[i] = x
    v = unit(rng)
    M = loguni(rng, 0.2, 20.0)

    def shape(ctx):
        return np.outer(np.interp(ctx['t'], tc, th), v)
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg at set-down', dict(tau_cool_s=tau_c, tc_dir=v)


def settle_mount_ringing(rng, L):
    """Damped rocking of the mount excited by the impact of the set-down (rotation about a
    horizontal axis: gravity direction oscillates, lever arm adds tangential acceleration)."""
    S = _settle_common(rng, L)
    fr = loguni(rng, 2.0, 25.0)
    w = 2 * np.pi * fr
    td = loguni(rng, 0.15, 2.5)
    tr = 0.25 / fr
    lev = max(np.linalg.norm(S.lever), 0.02)
    M = loguni(rng, 1.0, 200.0)   # mg peak specific-force swing
    th0 = M * 1e-3 / (1.0 + w * w * lev / G0)
    axes = np.array([horiz_axis(rng) for _ in range(S.n)])
    amp = th0 * rng.uniform(0.5, 1.0, S.n)
    ph = rng.uniform(0, 2 * np.pi, S.n)

    def pert(t):
        k, tau = S.last_landing(t)
        env = onset_env(tau, td, tr) / 0.6 * fade_after_hold(S, k, t)
        th = (amp[k] * env * np.sin(w * tau + ph[k]))[:, None] * axes[k]
        return th, np.zeros_like(th)
    S.perts.append(pert)
    return M, 'mg peak', dict(freq_hz=fr, decay_s=td, tilt_amp_rad=th0)


def settle_support_creep(rng, L):
    """Soft support (foam/rubber feet) creeps after set-down: the board slowly tilts and sinks."""
    S = _settle_common(rng, L)
    tau = loguni(rng, 1.0, min(20.0, max(2.0, np.mean(S.holds))))
    M = loguni(rng, 0.3, 20.0)    # mg ~ final tilt * 1 g
    axes = np.array([horiz_axis(rng) for _ in range(S.n)])
    amp = M * 1e-3 * rng.uniform(0.5, 1.0, S.n)
    sink = rng.uniform(0.2e-3, 2e-3, S.n)
    logc = bool(rng.uniform() < 0.3)

    def pert(t):
        k, tau_s = S.last_landing(t)
        if logc:
            g = np.log1p(np.maximum(tau_s, 0) / tau) / np.log1p(S.holds[k] / tau)
        else:
            g = 1 - np.exp(-np.maximum(tau_s, 0) / tau)
        g = g * smooth5(tau_s / 0.3) * fade_after_hold(S, k, t)
        th = (amp[k] * g)[:, None] * axes[k]
        dp = np.zeros_like(th)
        dp[:, 2] = -sink[k] * g
        return th, dp
    S.perts.append(pert)
    return M, 'mg tilt', dict(tau_s=tau, logarithmic=logc)


# =========================================================================================== motion
def _event_sum(t, events, fn, span):
    th = np.zeros((len(t), 3))
    dp = np.zeros((len(t), 3))
    for ev in events:
        i0, i1 = np.searchsorted(t, [ev['t0'], ev['t0'] + span(ev)])
        if i1 > i0:
            a, b = fn(ev, t[i0:i1] - ev['t0'])
            th[i0:i1] += a
            dp[i0:i1] += b
    return th, dp


def _pick_holds(rng, S, frac_lo, frac_hi, keep_still=0):
    m = max(2, min(int(round(S.n * rng.uniform(frac_lo, frac_hi))), S.n - keep_still))
    return np.sort(rng.choice(S.n, size=min(m, S.n), replace=False))


def _peak_dd(f, tau, tr):
    """Peak |d2/dt2| of onset_env(t) sin(2 pi f t) (unit displacement amplitude)."""
    x = np.linspace(0, 8 * tau + 5 * tr, 6000)
    y = onset_env(x, tau, tr) * np.sin(2 * np.pi * f * x)
    dx = x[1] - x[0]
    return float(np.max(np.abs(np.diff(y, 2))) / dx ** 2)


def motion_taps(rng, L):
    S = L.session()
    L.make_part()
    M = loguni(rng, 5.0, 600.0)   # mg peak linear acceleration of a tap
    hk = _pick_holds(rng, S, 0.2, 1.0)
    lev = np.linalg.norm(S.lever)
    events = []
    for k in hk:
        for _ in range(int(rng.integers(1, 4))):
            span = S.holds[k] - 0.6
            if span <= 0:
                continue
            f = rng.uniform(15.0, 60.0)
            d = unit(rng)
            d[2] *= 2.0
            d /= np.linalg.norm(d)
            tau = loguni(rng, 0.02, 0.25)
            fr = rng.uniform(4.0, 12.0)
            events.append(dict(t0=S.hs[k] + 0.2 + rng.uniform(0, span), f=f, tau=tau,
                               d=d, A=M * 1e-3 * G0 / _peak_dd(f, tau, 0.16 / f) * rng.uniform(0.4, 1.0),
                               fr=fr, ax=horiz_axis(rng),
                               th=0.3 * M * 1e-3 * rng.uniform(0.2, 1.0) / (1 + _peak_dd(fr, 3 * tau, 0.16 / fr) * lev / G0)))

    def one(ev, tau):
        e = onset_env(tau, ev['tau'], 0.16 / ev['f'])
        er = onset_env(tau, 3 * ev['tau'], 0.16 / ev['fr'])
        dp = (ev['A'] * e * np.sin(2 * np.pi * ev['f'] * tau))[:, None] * ev['d']
        th = (ev['th'] * er * np.sin(2 * np.pi * ev['fr'] * tau))[:, None] * ev['ax']
        return th, dp
    S.perts.append(lambda t: _event_sum(t, events, one, lambda ev: 12 * ev['tau'] + 0.1))
    return M, 'mg peak', dict(n_taps=len(events), holds_affected=hk)


def motion_sway(rng, L):
    """The support itself sways (floating floor, ship, flexing table): slow tilt + translation."""
    S = L.session()
    L.make_part()
    M = loguni(rng, 0.3, 40.0)   # mg ~ tilt amplitude * 1 g
    K = int(rng.integers(2, 5))
    fr = rng.uniform(0.1, 1.5, K)
    ph = rng.uniform(0, 2 * np.pi, K)
    axs = np.array([horiz_axis(rng) for _ in range(K)])
    amp = M * 1e-3 * rng.uniform(0.3, 1.0, K) / np.sqrt(K)
    tdir = np.array([unit(rng) for _ in range(K)])
    tamp = 0.5 * M * 1e-3 * G0 / (2 * np.pi * fr) ** 2 * rng.uniform(0, 1, K) / np.sqrt(K)

    def pert(t):
        s = np.sin(2 * np.pi * np.outer(t, fr) + ph)
        return (s * amp) @ axs, (s * tamp) @ tdir
    S.perts.append(pert)
    return M, 'mg tilt amp', dict(freqs_hz=fr)


def motion_handheld(rng, L):
    """Board held in the hand in some poses: physiological tremor 8-12 Hz plus slow hand sway."""
    S = L.session()
    L.make_part()
    M = loguni(rng, 2.0, 60.0)   # mg tremor acceleration (sum of amplitudes)
    hk = _pick_holds(rng, S, 0.25, 0.8, keep_still=9)
    prm = []
    for k in hk:
        K = 4
        fr = rng.uniform(8.0, 12.0, K)
        prm.append(dict(k=k, fr=fr, ph=rng.uniform(0, 2 * np.pi, K), d=np.array([unit(rng) for _ in range(K)]),
                        A=M * 1e-3 * G0 / (2 * np.pi * fr) ** 2 * rng.uniform(0.5, 1.0, K) / K * 2,
                        sf=rng.uniform(0.1, 1.0, 2), sph=rng.uniform(0, 2 * np.pi, 2),
                        sax=np.array([horiz_axis(rng), horiz_axis(rng)]),
                        sth=M * 1e-3 * rng.uniform(0.5, 3.0) * rng.uniform(0.3, 1, 2),
                        tf=rng.uniform(0.2, 0.8), td=unit(rng), tA=rng.uniform(0.3e-3, 2e-3)))

    def pert(t):
        th = np.zeros((len(t), 3))
        dp = np.zeros((len(t), 3))
        for p in prm:
            k = p['k']
            i0, i1 = np.searchsorted(t, [S.hs[k], S.he[k]])
            if i1 <= i0:
                continue
            ts = t[i0:i1]
            w = S.hold_window(ts, k, 0.5)[:, None]
            tr = np.sin(2 * np.pi * np.outer(ts, p['fr']) + p['ph'])
            dp[i0:i1] += w * ((tr * p['A']) @ p['d'] + np.outer(p['tA'] * np.sin(2 * np.pi * p['tf'] * ts), p['td']))
            sw = np.sin(2 * np.pi * np.outer(ts, p['sf']) + p['sph'])
            th[i0:i1] += w * ((sw * p['sth']) @ p['sax'])
        return th, dp
    S.perts.append(pert)
    return M, 'mg tremor', dict(holds_affected=hk)


def motion_footsteps(rng, L):
    """Someone walks past: floor vibration bursts at the step rate, each a damped 8-30 Hz ring."""
    S = L.session()
    L.make_part()
    D = S.duration
    lev = np.linalg.norm(S.lever)
    M = loguni(rng, 2.0, 200.0)   # mg peak vertical acceleration
    events = []
    n_ep = int(rng.integers(1, 4))
    for _ in range(n_ep):
        start = rng.uniform(0, max(1.0, D - 10))
        dur = rng.uniform(4.0, 15.0)
        rate = rng.uniform(1.6, 2.2)
        ff = rng.uniform(8.0, 30.0)
        nst = int(dur * rate)
        for j in range(nst):
            env = np.sin(np.pi * (j + 0.5) / nst)   # approaching, passing, leaving
            f = ff * rng.uniform(0.9, 1.1)
            d = np.array([0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=3)
            tau = rng.uniform(0.05, 0.2)
            events.append(dict(t0=start + j / rate + rng.normal(0, 0.02), f=f, tau=tau,
                               A=env * M * 1e-3 * G0 / _peak_dd(f, tau, 0.16 / f), d=d / np.linalg.norm(d),
                               ax=horiz_axis(rng), th=env * 0.1 * M * 1e-3 / (1 + _peak_dd(f, tau, 0.16 / f) * lev / G0)))
    events.sort(key=lambda e: e['t0'])

    def one(ev, tau):
        e = onset_env(tau, ev['tau'], 0.16 / ev['f'])
        s = np.sin(2 * np.pi * ev['f'] * tau)
        return (ev['th'] * e * s)[:, None] * ev['ax'], (ev['A'] * e * s)[:, None] * ev['d']
    S.perts.append(lambda t: _event_sum(t, events, one, lambda ev: 12 * ev['tau']))
    return M, 'mg peak', dict(episodes=n_ep, steps=len(events))


# ==================================================================================== colored noise
def _cn_base(rng, kind, D, dtc=0.05):
    tc = np.arange(0.0, D + 2 * dtc, dtc)
    n = len(tc)
    info = dict(kind=kind)
    if kind == 'random_walk':
        x = np.cumsum(rng.normal(size=(n, 3)), 0)
    elif kind == 'flicker':
        m = 2 * n
        F = np.fft.rfftfreq(m, dtc)
        amp = np.zeros_like(F)
        amp[1:] = 1.0 / np.sqrt(F[1:])
        X = (rng.normal(size=(len(F), 3)) + 1j * rng.normal(size=(len(F), 3))) * amp[:, None]
        x = np.fft.irfft(X, m, axis=0)[:n]
    elif kind == 'gauss_markov':
        tau = loguni(rng, 1.0, 100.0)
        a = np.exp(-dtc / tau)
        w = rng.normal(size=(n, 3)) * np.sqrt(1 - a * a)
        x = np.empty((n, 3))
        acc = rng.normal(size=3)
        for i in range(n):
            acc = a * acc + w[i]
            x[i] = acc
        info['tau_s'] = tau
    else:
        raise ValueError(kind)
    x = x - x.mean(0)
    x /= np.max(x.std(0))
    x *= rng.uniform(0.4, 1.0, 3)
    return tc, x, info


def _telegraph(rng, t, D):
    nsrc = int(rng.integers(1, 4))
    out = np.zeros((len(t), 3))
    info = []
    for s in range(nsrc):
        d = np.eye(3)[rng.integers(3)] if rng.uniform() < 0.6 else unit(rng)
        h = rng.uniform(0.4, 1.0) * (1.0 if s == 0 else rng.uniform(0.2, 1.0))
        mu = (loguni(rng, 0.3, 20.0), loguni(rng, 0.3, 20.0))
        sw = []
        x = -rng.uniform(0, mu[0])
        st = 0
        while x < D:
            x += rng.exponential(mu[st])
            sw.append(x)
            st ^= 1
        cnt = np.searchsorted(np.array(sw), t, 'right')
        out += np.outer((cnt % 2) * h, d)
        info.append(dict(dir=d, level=h, dwell_s=list(mu), switches=len(sw)))
    return out - out.mean(0), info


def _colored(kind):
    def fn(rng, L):
        S = L.session()
        L.make_part()
        maybe_flat_temp(rng, L, 0.15)
        D = S.duration
        M = loguni(rng, 0.05, 6.0)  # mg rms of the coloured bias component
        p = dict(kind=kind)
        if kind in ('random_walk', 'flicker', 'gauss_markov'):
            tc, x, info = _cn_base(rng, kind, D)
            p.update(info)

            def shape(ctx):
                return np.stack([np.interp(ctx['t'], tc, x[:, j]) for j in range(3)], 1)
            L.effects.append(normalise(shape, M, 'std'))
        elif kind == 'telegraph':
            def shape(ctx):
                return _telegraph(rng, ctx['t'], D)[0]
            L.effects.append(normalise(shape, M, 'std'))
        else:  # mixture
            parts = list(rng.choice(['random_walk', 'flicker', 'gauss_markov', 'telegraph'],
                                    size=int(rng.integers(2, 4)), replace=False))
            comps = []
            for kd in parts:
                wgt = rng.uniform(0.2, 1.0)
                if kd == 'telegraph':
                    comps.append((kd, wgt, None, None))
                else:
                    tc, x, info = _cn_base(rng, kd, D)
                    comps.append((kd, wgt, tc, x))
            p['components'] = parts

            def shape(ctx):
                t = ctx['t']
                y = np.zeros((len(t), 3))
                for kd, wgt, tc, x in comps:
                    if kd == 'telegraph':
                        z, _ = _telegraph(rng, t, D)
                        z /= max(np.max(z.std(0)), 1e-12)
                    else:
                        z = np.stack([np.interp(t, tc, x[:, j]) for j in range(3)], 1)
                    y += wgt * z
                return y
            L.effects.append(normalise(shape, M, 'std'))
        return M, 'mg rms', p
    return fn


# ================================================================================= out-of-catalogue
def _ooc_common(rng, L):
    S = L.session()
    L.make_part()
    maybe_flat_temp(rng, L, 0.15)
    return S


def ooc_prev_pose_hysteresis(rng, L):
    """Bias in a pose remembers the previous pose's gravity direction (mechanical/charge memory)."""
    S = _ooc_common(rng, L)
    Pm = rng.normal(size=(3, 3))
    prev = np.vstack([unit(rng)[None], S.ups[:-1]])
    bk = prev @ Pm.T
    M = loguni(rng, 0.2, 15.0)

    def shape(ctx):
        k, _ = S.last_landing(ctx['t'])
        return bk[k]
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg peak', dict(memory_matrix=Pm)


def ooc_approach_direction(rng, L):
    """Bias depends on the sense of the last rotation (approach direction) about a sensor axis."""
    S = _ooc_common(rng, L)
    n = unit(rng)
    u = unit(rng)
    sg = np.concatenate([[rng.choice([-1.0, 1.0])], np.sign(S.w @ n + 1e-12)])
    M = loguni(rng, 0.2, 15.0)

    def shape(ctx):
        k, _ = S.last_landing(ctx['t'])
        return np.outer(sg[k], u)
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg peak', dict(axis=n, dir=u)


def ooc_cross_product(rng, L):
    """Bilinear cross-axis terms: each axis picks up c * a_j * a_k."""
    S = _ooc_common(rng, L)
    C = rng.normal(size=(3, 3)) * (rng.uniform(size=(3, 3)) < 0.7)
    if not C.any():
        C[0, 0] = 1.0
    M = loguni(rng, 0.2, 15.0)

    def shape(ctx):
        x = ctx['Af']
        prod = np.stack([x[:, 1] * x[:, 2], x[:, 0] * x[:, 2], x[:, 0] * x[:, 1]], 1)  # yz, xz, xy
        return prod @ C.T
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg peak', dict(coef_shape=C, pairs=['yz', 'xz', 'xy'])


def ooc_bad_pose(rng, L):
    """One (or two) poses rest on a cable: the flexed board stresses the package -> bias offset."""
    S = _ooc_common(rng, L)
    nb = 1 if rng.uniform() < 0.75 else 2
    bad = rng.choice(S.n, size=nb, replace=False)
    off = np.zeros((S.n, 3))
    for b in bad:
        off[b] = unit(rng) * rng.uniform(0.6, 1.0)
    M = loguni(rng, 0.5, 25.0)

    def shape(ctx):
        k, _ = S.last_landing(ctx['t'])
        return off[k]
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg offset', dict(bad_poses=bad)


def ooc_bias_step(rng, L):
    """A sudden permanent bias shift (shock, ESD, register glitch) at one moment."""
    S = _ooc_common(rng, L)
    ts = S.duration * rng.uniform(0.3, 0.75)
    d = unit(rng)
    M = loguni(rng, 0.3, 20.0)

    def eff(ctx):
        return np.outer((ctx['t'] >= ts).astype(float), d) * M * 1e-3
    L.effects.append(eff)
    return M, 'mg step', dict(t_step_s=ts, dir=d)


def ooc_mains_pickup(rng, L):
    """Electrical pickup (mains harmonic or motor drive) added after the digital filter, aliased."""
    S = _ooc_common(rng, L)
    fs = L.part.fs
    for _ in range(50):
        if rng.uniform() < 0.6:
            f = rng.choice([50.0, 60.0]) * int(rng.integers(1, 4)) * (1 + rng.normal(0, 5e-4))
            src = 'mains'
        else:
            f = rng.uniform(23.0, 400.0)
            src = 'motor'
        fa = abs(f - fs * np.round(f / fs))
        if 0.5 <= fa <= fs / 2 - 0.5:
            break
    else:
        f = fs * 0.5 * 0.37
        src = 'fallback'
        fa = f
    d = unit(rng)
    ph = rng.uniform(0, 2 * np.pi)
    M = loguni(rng, 0.3, 20.0)
    amdepth = rng.uniform(0, 0.5)
    amf = rng.uniform(0.01, 0.2)

    def eff(ctx):
        t = ctx['t']
        a = (1 + amdepth * np.sin(2 * np.pi * amf * t)) * np.sin(2 * np.pi * f * t + ph)
        return np.outer(a, d) * M * 1e-3
    L.post.append(eff)
    return M, 'mg amplitude', dict(source=src, f_hz=f, alias_hz=fa, dir=d)


def ooc_flex_orientation(rng, L):
    """Board sags under its own weight only in some orientations (e.g. upside down or on an edge):
    stress bias grows as a threshold power law of the gravity component along one axis."""
    S = _ooc_common(rng, L)
    ax = int(rng.integers(3))
    sgn = rng.choice([-1.0, 1.0])
    s0 = rng.uniform(0.2, 0.6)
    pw = rng.uniform(1.0, 2.0)
    u = unit(rng)
    M = loguni(rng, 0.3, 15.0)

    def shape(ctx):
        s = sgn * ctx['f'][:, ax]
        return np.outer(np.maximum(s - s0, 0.0) ** pw, u)
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg peak', dict(axis=ax, sign=sgn, threshold_g=s0, power=pw, dir=u)


def ooc_g_misalignment(rng, L):
    """Non-orthogonality that depends on gravity along one axis (proof mass/pivot deformation)."""
    S = _ooc_common(rng, L)
    j = int(rng.integers(3))
    Sm = rng.normal(size=(3, 3))
    Sm = Sm + Sm.T
    np.fill_diagonal(Sm, 0.0)
    M = loguni(rng, 0.2, 15.0)

    def shape(ctx):
        return ctx['f'][:, j:j + 1] * (ctx['Af'] @ Sm.T)
    L.effects.append(normalise(shape, M, 'peak'))
    return M, 'mg peak', dict(axis=j, sym_shape=Sm)


def ooc_bit_glitch(rng, L):
    """Sporadic bus errors: single samples with one flipped bit in one axis."""
    S = _ooc_common(rng, L)
    P = L.part
    L.part.units = 'counts' if rng.uniform() < 0.7 else P.units
    cands = [b for b in range(P.bits - 1) if 0.02 <= 2 ** b / P.lsb_per_g <= 1.0] or [P.bits - 4]
    nerr = int(rng.integers(3, 40))
    bits = rng.choice(cands, nerr)
    info = dict(n_glitches=nerr, bits=bits)
    mag = float(np.median(2.0 ** bits / P.lsb_per_g) * 1000)

    def hook(ctx, c):
        N = len(c)
        idx = rng.integers(0, N, nerr)
        axs = rng.integers(0, 3, nerr)
        B = P.bits
        mask = (1 << B) - 1
        for i, a, b in zip(idx, axs, bits):
            u = int(c[i, a]) & mask
            u ^= (1 << int(b))
            c[i, a] = u - (1 << B) if u >= (1 << (B - 1)) else u
        return c
    L.count_hooks.append(hook)
    return mag, 'mg spike (median)', info


# ========================================================================================== catalogue
FAMILY_SHAPES = {
    'clean': [('standard', clean_standard), ('coarse_quant', clean_coarse_quant), ('lowpass', clean_lowpass),
              ('jitter', clean_jitter), ('short_holds', clean_short_holds), ('long_holds', clean_long_holds),
              ('jig_temp', clean_jig_temp), ('noisy_fast', clean_noisy_fast)],
    'drift': [('warmup_exp', drift_warmup), ('ageing_poly', drift_ageing_poly), ('wander', drift_wander),
              ('log_creep', drift_log_creep), ('supply_sag', drift_supply_sag), ('scale_drift', drift_scale)],
    'temperature': [('warmup', _temperature('warmup')), ('cooling', _temperature('cooling')),
                    ('room_cycle', _temperature('room_cycle')), ('self_heating', _temperature('self_heating')),
                    ('chamber_ramp', _temperature('chamber_ramp'))],
    'scale-nonlinearity': [('quadratic', _nl('quadratic')), ('cubic', _nl('cubic')), ('mixed', _nl('mixed')),
                           ('single_axis', _nl('single_axis')), ('soft_saturation', _nl('soft_saturation')),
                           ('odd_abs', _nl('odd_abs'))],
    'settling': [('exp_offset', settle_exp_offset), ('two_stage', settle_two_stage),
                 ('thermal_touch', settle_thermal_touch), ('mount_ringing', settle_mount_ringing),
                 ('support_creep', settle_support_creep)],
    'motion': [('taps', motion_taps), ('sway', motion_sway), ('handheld', motion_handheld),
               ('footsteps', motion_footsteps)],
    'colored-noise': [('random_walk', _colored('random_walk')), ('flicker', _colored('flicker')),
                      ('gauss_markov', _colored('gauss_markov')), ('telegraph', _colored('telegraph')),
                      ('mixture', _colored('mixture'))],
    'out-of-catalogue': [('prev_pose_hysteresis', ooc_prev_pose_hysteresis),
                         ('approach_direction', ooc_approach_direction), ('cross_product', ooc_cross_product),
                         ('bad_pose', ooc_bad_pose), ('bias_step', ooc_bias_step),
                         ('mains_pickup', ooc_mains_pickup), ('flex_orientation', ooc_flex_orientation),
                         ('g_misalignment', ooc_g_misalignment), ('bit_glitch', ooc_bit_glitch)],
}
