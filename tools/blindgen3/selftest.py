#!/usr/bin/env python3
"""Self-test of blindgen3 against its own physics (never against accelcal).

    python3 tools/blindgen3/selftest.py

Each check prints PASS/FAIL with the measured figure; exit status 1 if any fails.
"""

import json
import os
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import chain  # noqa: E402
import effects as fx  # noqa: E402
import generate  # noqa: E402
import parts  # noqa: E402
import session  # noqa: E402

FAILS = []


def check(name, ok, detail):
    print(f"{'PASS' if ok else 'FAIL'}  {name}: {detail}")
    if not ok:
        FAILS.append(name)


def build(seed, style, odr=100.0, n_poses=12, part="ICM-42688-P", scenario="ordinary"):
    rng = np.random.default_rng(seed)
    unit = parts.draw_unit(rng, name=part, odr=odr)
    st = session.plan(rng, style, n_poses)
    k = int(np.clip(1600 // odr, 2, 8))
    fs = k * unit["odr_true_hz"]
    segs, total = session.timeline(st)
    t = np.arange(int(total * fs)) / fs
    R, P = session.trajectory(st, t, segs, rng)
    T, _ = session.temperature(rng, t, segs, unit["ds"], scenario)
    ctx = chain.Ctx(t, fs, segs, st, R, P, T, unit)
    ctx.k = k
    return ctx, rng


def hold_means(ctx, y, trim=0.5):
    out = []
    for a, b, _ in ctx.holds:
        m = (ctx.t >= a + trim) & (ctx.t < b - trim)
        out.append(y[m].mean(0))
    return np.array(out)


def main():
    rng = np.random.default_rng(0)
    # 1. rotations
    v = rng.normal(size=(50, 3))
    v *= (rng.uniform(0, 3.1, 50) / np.linalg.norm(v, axis=1))[:, None]
    Rs = session.exp_so3(v)
    err = max(np.linalg.norm(session.log_so3(R) - vi) for R, vi in zip(Rs, v))
    orth = np.abs(Rs @ Rs.transpose(0, 2, 1) - np.eye(3)).max()
    check("exp/log SO(3) round trip", err < 1e-9 and orth < 1e-12, f"max err {err:.2e}, orthogonality {orth:.1e}")

    # 2. static holds feel exactly 1 g; moves do not (every style)
    for i, style in enumerate(session.STYLES):
        ctx, _ = build(10 + i, style)
        f = chain.specific_force(ctx) / parts.G0
        hm = ctx.hold_mask(trim=0.05)
        dev = np.abs(np.linalg.norm(f[hm], axis=1) - 1).max()
        mv = ~ctx.hold_mask(trim=-0.0)
        dyn = np.abs(np.linalg.norm(f[mv], axis=1) - 1).max()
        # the gravity direction in a hold is R^T e_z of its pose
        hmns = hold_means(ctx, f, 0.05)
        ups = np.array([ctx.poses[k][2, :] for _, _, k in ctx.holds])
        derr = np.abs(hmns - ups).max()
        check(f"{style}: |f| = 1 g in holds", dev < 1e-9 and derr < 1e-9 and dyn > 0.01,
              f"max | |f|-1 | {dev:.1e} g, direction err {derr:.1e}, max in moves {dyn:.3f} g")

    # 3. digital low-pass: DC gain 1, -3 dB at the cut-off
    fs, fc = 800.0, 40.0
    t = np.arange(40000) / fs
    x = np.stack([np.ones_like(t), np.sin(2 * np.pi * fc * t), np.sin(2 * np.pi * 4 * fc * t)], 1)
    y = chain.lowpass(x, fs, fc)[5000:-5000]
    g_dc = y[:, 0].mean()
    g_fc = y[:, 1].std() * np.sqrt(2)
    g_4 = y[:, 2].std() * np.sqrt(2)
    check("low-pass gains", abs(g_dc - 1) < 1e-9 and abs(g_fc - 2 ** -0.5) < 0.01 and abs(g_4 - 1 / 257 ** 0.5) < 0.005,
          f"DC {g_dc:.6f}, at fc {g_fc:.4f} (0.7071), at 4 fc {g_4:.4f} (1/sqrt(1+4^4) = 0.0624)")

    # 4. white noise after the low-pass: std = nd sqrt(ENBW), ENBW = 1.1107 fc for Butterworth-2
    nd = 100e-6
    w = rng.normal(size=(400000, 3)) * chain.white_std(nd, fs)
    s = chain.lowpass(w, fs, fc)[::8].std()
    pred = nd * np.sqrt(np.pi / (4 * np.sin(np.pi / 4)) * fc)
    check("white noise through the low-pass", abs(s / pred - 1) < 0.03, f"std {s * 1e6:.1f} ug vs {pred * 1e6:.1f} ug")

    # 5. a clean log's hold means are the linear model of the part (gain, offset) to within noise
    ctx, r = build(21, "table-books", odr=200.0, part="BMI088")
    t_s, y_s, idx, mag = chain.run_part(ctx, r)
    ups = np.array([ctx.poses[k][2, :] for _, _, k in ctx.holds])
    pred = ups @ ctx.unit["gain"].T + ctx.unit["offset_g"]
    got = []
    for a, b, _ in ctx.holds:
        m = (t_s >= a + 0.5) & (t_s < b - 0.5)
        got.append(y_s[m].mean(0))
    res = np.abs(np.array(got) - pred).max()
    check("clean: hold means = Ka-model", res < 3e-4 and mag == 0.0, f"max residual {res * 1e3:.3f} mg, magnitude {mag}")

    # 6. temperature injector: hold means follow tco * dT (regression recovers tco)
    ctx, r = build(22, "gimbal", part="ICM-42688-P", scenario="chamber-ramp")
    p = fx.temp_bias(ctx, r, 1.0)
    f = chain.sensed(ctx, chain.specific_force(ctx), True) - chain.sensed(ctx, chain.specific_force(ctx), False)
    b_est = np.linalg.lstsq(np.column_stack([ctx.T_die - ctx.T_die[0]]), f @ np.linalg.inv(ctx.unit["gain"]).T, rcond=None)[0][0]
    check("temperature bias recovers tco", np.allclose(b_est * 1e3, p["tco_mg_per_k"], rtol=0, atol=1e-4),
          f"{np.round(b_est * 1e3, 4).tolist()} vs {p['tco_mg_per_k']} mg/K")

    # 7. non-linearity: the extra output is k2 a^2 + k3 a^3 exactly
    ctx, r = build(23, "table-books")
    p = fx.nl_mixed(ctx, r, 0.5)
    a = chain.specific_force(ctx) / parts.G0
    extra = ctx.nonlin[0](a)
    want = np.array(p["k2_mg_per_g2"]) * 1e-3 * a ** 2 + np.array(p["k3_mg_per_g3"]) * 1e-3 * a ** 3
    check("non-linearity polynomial", np.abs(extra - want).max() < 1e-6,
          f"(parameters reported to 1e-4 mg) max diff {np.abs(extra - want).max():.1e} g")

    # 8. Gauss-Markov noise: std and correlation time as drawn
    ctx, r = build(24, "table-books", n_poses=40)
    ctx.t = np.arange(2_000_000) / 100.0
    ctx.fs = 100.0
    ctx.noise = np.zeros((len(ctx.t), 3))
    p = fx.cn_gauss_markov(ctx, r, 0.5)
    x = ctx.noise[:, 0]
    lag = int(p["tau_s"] * 100)
    rho = np.corrcoef(x[:-lag], x[lag:])[0, 1]
    check("Gauss-Markov correlation at tau", abs(rho - np.exp(-1)) < 0.08,
          f"rho(tau) {rho:.3f} (e^-1 = 0.368), std {x.std() * 1e3:.3f} mg (sigma {p['sigma_mg']} mg x 0.5-1)")

    # 9. random walk: variance grows as K^2 t
    ctx.noise = np.zeros((len(ctx.t), 3))
    p = fx.cn_random_walk(ctx, r, 0.5)
    d = ctx.noise[1000:, 0] - ctx.noise[:-1000, 0]  # 10 s increments
    K = d.std() / np.sqrt(10.0)
    check("random walk coefficient", p["k_ug_per_rts"] * 0.45 < K * 1e6 < p["k_ug_per_rts"] * 1.05,
          f"{K * 1e6:.2f} ug/sqrt(s) measured, drawn {p['k_ug_per_rts']} x 0.5-1")

    # 10. polling read-out: duplicates + skips follow the clock mismatch
    ts = np.arange(200000) / (100.0 * 1.02)
    st, idx, info = chain.readout(np.random.default_rng(5), ts, 100.0, "poll")
    frac = info["skipped"] / len(idx)
    check("polling skips with a 2 % fast sensor", 0.01 < frac < 0.03 and np.all(np.diff(st) > 0),
          f"skipped {frac * 100:.2f} % of polls, duplicates {info['duplicates']}, stamps increasing")

    # 11. every injector: finite output, a measurable effect that grows with the level
    bad, n_inj = [], 0
    for fam, (_, shapes) in generate.FAMILIES.items():
        for shape, inj in shapes.items():
            if inj is None:
                continue
            n_inj += 1
            mags = []
            for lvl in (0.0, 1.0):
                ctx, r = build(30, generate.STYLES_FOR.get(shape, session.STYLES)[0], odr=100.0,
                               scenario="chamber-ramp" if fam == "temperature" else "ordinary")
                inj(ctx, np.random.default_rng(7), lvl)
                t_s, y_s, idx, mag = chain.run_part(ctx, r)
                if not np.all(np.isfinite(y_s)):
                    mag = float("nan")
                mags.append(mag)
            if not (mags[0] > 0 and mags[1] > mags[0]):
                bad.append(f"{fam}/{shape} {mags}")
    check("every injector acts and grows with its level", not bad, "; ".join(bad) or f"{n_inj} injectors, magnitude at level 0 < level 1")

    # 12. end to end: --small logs, manifest, row cap, units
    with tempfile.TemporaryDirectory() as d:
        generate.main(["--out", d, "--per-family", "1", "--seed", "3", "--small",
                       "--families", "clean,temperature,out-of-catalogue"])
        man = json.load(open(os.path.join(d, "manifest.json")))
        ok = True
        for e in man:
            need = {"file", "family", "shape", "seed", "magnitude", "magnitude_unit", "unit", "expected"}
            ok &= need <= set(e) and 12 <= e["poses"] <= 16 and e["odr_hz"] == 100.0
            data = np.loadtxt(os.path.join(d, e["file"]), delimiter=",", skiprows=1)
            ok &= len(data) == e["rows"] <= 250_000 and np.all(np.diff(data[:, 0]) > 0)
            ok &= (data.shape[1] == 5) == e["temp"]
            if e["family"] == "temperature":
                ok &= e["temp"] and e["magnitude"] > 0
            if e["family"] == "clean":
                ok &= e["magnitude"] == 0.0
        check("--small end to end", bool(ok), f"{len(man)} logs, fields/poses/rate/rows/time/temp checked")

    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    sys.exit(1 if FAILS else 0)


if __name__ == "__main__":
    main()
