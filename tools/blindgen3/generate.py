#!/usr/bin/env python3
"""blindgen3: labelled raw logs of accelerometer calibration sessions, simulated from the physics.

    python3 tools/blindgen3/generate.py --out DIR --per-family N --seed S [--small] [--families a,b]

Writes DIR/<family>-<shape>-<i>.csv and DIR/manifest.json (read by tools/blindgen2/score.py).
Each log: a session style moves a rigid body through 12-40 poses (session.py), a MEMS part
drawn within its datasheet tolerances senses it (parts.py, chain.py), exactly one effect of
the log's family is injected (effects.py, none for `clean`), and a logger reads it out.
"""

import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import chain  # noqa: E402
import effects as fx  # noqa: E402
import parts  # noqa: E402
import session  # noqa: E402

MAX_ROWS = 240_000
MAG_UNIT = "mg rms over holds (effect's change of the output, hold mean removed)"

# family -> (expected verdict, {shape: injector or None})
FAMILIES = {
    "clean": ("none", {"plain": None, "coarse": None, "warm": None, "polled": None}),
    "drift": ("drift", {"linear": fx.drift_linear, "log-creep": fx.drift_log_creep,
                        "exp-relax": fx.drift_exp_relax, "supply-sag": fx.drift_supply_sag}),
    "temperature": ("temperature", {"bias": fx.temp_bias, "scale": fx.temp_scale,
                                    "bias-scale": fx.temp_bias_scale, "bias-lagged": fx.temp_bias_lagged,
                                    "bias-quadratic": fx.temp_bias_quadratic}),
    "scale-nonlinearity": ("scale-nonlinearity", {"quadratic": fx.nl_quadratic, "cubic": fx.nl_cubic,
                                                  "mixed": fx.nl_mixed, "z-only": fx.nl_z_only}),
    "settling": ("settling", {"creep-tilt": fx.settle_creep_tilt, "ringing": fx.settle_ringing,
                              "bias-recovery": fx.settle_bias_recovery,
                              "thermal-touch": fx.settle_thermal_touch}),
    "motion": ("motion", {"taps": fx.motion_taps, "hand-held": fx.motion_hand_held,
                          "nudge": fx.motion_nudge, "footsteps": fx.motion_footsteps}),
    "colored-noise": ("colored-noise", {"flicker": fx.cn_flicker, "gauss-markov": fx.cn_gauss_markov,
                                        "random-walk": fx.cn_random_walk, "popcorn": fx.cn_popcorn}),
    "out-of-catalogue": ("honest", {"clamp-pose": fx.ooc_clamp_pose, "motor-vibration": fx.ooc_motor_vibration,
                                    "hysteresis": fx.ooc_hysteresis, "cross-bilinear": fx.ooc_cross_bilinear,
                                    "offset-step": fx.ooc_offset_step}),
}


# shapes that only make physical sense in some session styles (a rigid gimbal does not creep
# on foam, nobody hand-holds a gimbal); every other shape may meet any style
STYLES_FOR = {
    "creep-tilt": ("table-books", "phone-free"),
    "ringing": ("gimbal", "cube-jig", "table-books"),
    "hand-held": ("phone-free", "table-books"),
    "nudge": ("table-books", "cube-jig", "phone-free"),
    "clamp-pose": ("table-books", "cube-jig"),
}


def log_seed(seed, fam_index, i):
    """The seed of one log: reproducible from (master seed, family index, log index)."""
    return int(seed) * 100_000 + fam_index * 1000 + i


def thermometer(rng, unit, t_int, T_die):
    """What the logged temperature column reads on the internal grid: the part's own die
    thermometer (its LSB and update rate) or, for parts without one, a board thermometer
    (0.0625 degC LSB, 4 Hz) that sees the die temperature through a 10-40 s lag.
    Both have a fixed calibration error of +-2 degC and 0.02-0.06 degC rms noise."""
    ds = unit["ds"]
    err = rng.uniform(-2, 2)
    if ds["temp_lsb_c"] is None:
        lsb, upd = 0.0625, 4.0
        T = fx.lag1(T_die, 1 / (t_int[1] - t_int[0]), rng.uniform(10, 40))
        src = "board"
    else:
        lsb, upd, T, src = ds["temp_lsb_c"], ds["temp_update_hz"], T_die, "die"
    T = T + err + rng.normal(0, rng.uniform(0.02, 0.06), len(T))
    if upd:
        fs = 1 / (t_int[1] - t_int[0])
        step = max(1, int(round(fs / upd)))
        T = np.repeat(T[::step], step)[:len(T)]
    return np.round(T / lsb) * lsb, dict(source=src, lsb_c=lsb, update_hz=upd, cal_err_c=round(err, 3))


def make_log(out_dir, family, fam_index, shape, i, seed, small):
    """Simulate one log, write its CSV; return its manifest entry."""
    ls = log_seed(seed, fam_index, i)
    rng = np.random.default_rng(ls)
    expected, shapes = FAMILIES[family]
    inj = shapes[shape]
    lvl = float(rng.uniform())
    style = str(rng.choice(STYLES_FOR.get(shape, session.STYLES)))
    coarse = family == "clean" and shape == "coarse"
    unit = parts.draw_unit(rng, coarse=coarse, small=small)
    odr = unit["odr_nom_hz"]
    n_poses = int(rng.integers(12, 17) if small else rng.integers(12, 41))
    st = session.plan(rng, style, n_poses)
    k = int(np.clip(1600 // odr, 2, 8))
    fs = k * unit["odr_true_hz"]
    st = session.fit_budget(st, odr, min(MAX_ROWS, chain.MAX_INTERNAL / k))
    segs, total = session.timeline(st)
    t = np.arange(int(total * fs)) / fs
    R, P = session.trajectory(st, t, segs, rng)
    scenario = "ordinary"
    if family == "temperature":
        scenario = str(rng.choice(["power-up", "from-cold", "chamber-ramp"]))
    elif family == "clean" and shape == "warm":
        scenario = str(rng.choice(["power-up", "from-cold"]))
    elif family == "drift":
        scenario = "warmed-up"
    T_die, tpar = session.temperature(rng, t, segs, unit["ds"], scenario, hand=style != "gimbal")
    ctx = chain.Ctx(t, fs, segs, st, R, P, T_die, unit)
    ctx.k = k
    params = inj(ctx, rng, lvl) if inj is not None else {}
    t_s, y_s, idx_s, mag = chain.run_part(ctx, rng)
    codes = chain.quantise(y_s, unit)
    mode = "poll" if (family == "clean" and shape == "polled") else str(rng.choice(["poll", "fifo-count", "fifo-batch"]))
    stamps, ridx, rinfo = chain.readout(rng, t_s, odr, mode)
    has_temp = family == "temperature" or (family == "clean" and shape == "warm") or bool(rng.random() < 0.5)
    out_unit = str(rng.choice(["counts", "g", "mps2"], p=[0.4, 0.35, 0.25]))
    t_host = stamps + (0.0 if rng.random() < 0.5 else round(float(rng.uniform(0, 5000)), 3))
    cols, fmts = [t_host], ["%.6f"]
    c = codes[ridx]
    if out_unit == "counts":
        names = ["t", "ax", "ay", "az"]
        cols += [c[:, 0], c[:, 1], c[:, 2]]
        fmts += ["%d"] * 3
    elif out_unit == "g":
        names = ["t", "ax (g)", "ay (g)", "az (g)"]
        v = c / unit["lsb_per_g"]
        cols += [v[:, 0], v[:, 1], v[:, 2]]
        fmts += ["%.7f"] * 3
    else:
        g_drv = float(rng.choice([9.80665, 9.81]))
        names = ["t", "ax (m/s^2)", "ay (m/s^2)", "az (m/s^2)"]
        v = c / unit["lsb_per_g"] * g_drv
        cols += [v[:, 0], v[:, 1], v[:, 2]]
        fmts += ["%.6f"] * 3
    tinfo = None
    if has_temp:
        Tlog, tinfo = thermometer(rng, unit, t, T_die)
        names.append("temp")
        cols.append(Tlog[idx_s[ridx]])
        fmts.append("%.4f")
    fname = f"{family}-{shape}-{i:03d}.csv"
    np.savetxt(os.path.join(out_dir, fname), np.column_stack(cols), fmt=fmts, delimiter=",",
               header=",".join(names), comments="")
    return dict(file=fname, family=family, shape=shape, seed=ls, magnitude=round(mag, 5),
                magnitude_unit=MAG_UNIT, unit=out_unit, expected=expected, level=round(lvl, 4),
                params=params, style=style, part=unit["part"], range_g=unit["range_g"],
                bits=unit["bits"], odr_hz=round(odr, 3), odr_true_hz=round(unit["odr_true_hz"], 4),
                bw_hz=round(unit["bw_hz"], 3), noise_ug_rthz=unit["nd_g"] * 1e6, poses=n_poses,
                duration_s=round(float(total), 2), rows=int(len(ridx)), readout=rinfo,
                temp=has_temp, temp_scenario=tpar, thermometer=tinfo, small=small)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--per-family", type=int, default=4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--small", action="store_true", help="12-16 poses at 100 Hz")
    ap.add_argument("--families", default=",".join(FAMILIES), help="comma-separated subset")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    fams = [f for f in a.families.split(",") if f]
    manifest = []
    for fam in fams:
        fi = list(FAMILIES).index(fam)
        shapes = list(FAMILIES[fam][1])
        off = int(np.random.default_rng([a.seed, fi]).integers(0, len(shapes)))
        for i in range(a.per_family):
            shape = shapes[(i + off) % len(shapes)]
            e = make_log(a.out, fam, fi, shape, i, a.seed, a.small)
            manifest.append(e)
            print(f"{e['file']:<44} {e['style']:<12} {e['part']:<12} {e['odr_hz']:>7.1f} Hz "
                  f"{e['rows']:>7} rows {e['unit']:<6} mag {e['magnitude']:.4g} mg", flush=True)
    with open(os.path.join(a.out, "manifest.json"), "w") as fh:
        json.dump(manifest, fh, indent=1, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))
    print(f"{len(manifest)} logs in {a.out}")


if __name__ == "__main__":
    main()
