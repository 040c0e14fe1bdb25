#!/usr/bin/env python3
"""Independent generator of labelled accelerometer calibration logs (numpy + stdlib).

    python3 tools/blindgen2/generate.py --out DIR --per-family N --seed S [--small]
        [--families clean,drift,...]

Writes DIR/<family>_<shape>_<i>.csv and DIR/manifest.json.  See README.md.
"""

import argparse
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import injectors as inj  # noqa: E402
from physics import Session, loguniform, render, write_csv  # noqa: E402

UNITS = ("counts", "g", "m/s^2")


# ------------------------------------------------------------------ shapes
# Each shape: fn(session, rng, u) -> (magnitude, magnitude_unit, params).  u in [0, 1) is
# the position of the log in the shape's magnitude range (log scale), so a run of N logs
# sweeps from barely visible to strong.  Ranges are physical (see injectors.py).

def lu(u, lo, hi):
    return float(math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo))))


def ambient_column(s, rng, p=0.25):
    """Some loggers write the (flat) room temperature anyway."""
    if rng.random() < p:
        T, _ = inj.temp_profile(s, rng, "ambient", 0.0)
        s.set_temperature(T)


# clean ---------------------------------------------------------------------------
def clean_plain(s, rng, u):
    ambient_column(s, rng)
    return 0.0, "-", {}


def clean_temp_inert(s, rng, u):
    kind = str(rng.choice(["warmup", "updown", "cycle"]))
    T, prm = inj.temp_profile(s, rng, kind, loguniform(rng, 2.0, 15.0))
    s.set_temperature(T)
    return 0.0, "-", prm


# drift ---------------------------------------------------------------------------
def drift_warmup(s, rng, u):
    m = lu(u, 0.3, 8.0)
    ambient_column(s, rng, 0.0)
    return m, "mg", inj.drift_warmup(s, rng, m)


def drift_wander(s, rng, u):
    m = lu(u, 0.1, 3.0)
    ambient_column(s, rng)
    return m, "mg rms", inj.drift_wander(s, rng, m)


def drift_ramp(s, rng, u):
    m = lu(u, 0.3, 8.0)
    ambient_column(s, rng, 0.0)
    return m, "mg", inj.drift_ramp(s, rng, m)


# temperature ---------------------------------------------------------------------
def _temp(s, rng, u, bias, scale, lag):
    """Temperature profile of 3-20 degC; tempcos from the datasheet ranges stretched down:
    zero-g 0.05-1.2 mg/degC, sensitivity 0.003-0.05 %/degC (u sweeps them).  The
    magnitude is the resulting peak effect over the die's temperature span (mg; for the
    scale, mg at 1 g)."""
    kind = str(rng.choice(["warmup", "updown", "cycle"]))
    dT = loguniform(rng, 3.0, 20.0)
    T, prm = inj.temp_profile(s, rng, kind, dT)
    s.set_temperature(T)
    Td = T
    if lag:
        tau = loguniform(rng, 20.0, 200.0)
        Td = inj.thermal_lag(s, T, tau)
        prm["lag_s"] = round(tau, 1)
    span = float(Td.max() - Td.min())
    m = 0.0
    if bias:
        tcb = lu(u, 0.05, 1.2)
        prm.update(inj.temperature_bias(s, rng, Td, tcb))
        m += tcb * span
    if scale:
        tcs = lu(u, 0.003, 0.05)
        prm.update(inj.temperature_scale(s, rng, Td, tcs))
        m += tcs * 10 * span
    prm["die_span_c"] = round(span, 2)
    return m, "mg peak over the die temperature span", prm


def temp_bias(s, rng, u):
    return _temp(s, rng, u, True, False, False)


def temp_scale(s, rng, u):
    return _temp(s, rng, u, False, True, False)


def temp_bias_scale(s, rng, u):
    return _temp(s, rng, u, True, True, False)


def temp_bias_lag(s, rng, u):
    return _temp(s, rng, u, True, False, True)


def temp_scale_lag(s, rng, u):
    return _temp(s, rng, u, False, True, True)


# scale non-linearity -------------------------------------------------------------
def nl_even(s, rng, u):
    m = lu(u, 0.3, 15.0)
    ambient_column(s, rng)
    return m, "mg at 1 g", inj.nonlin_poly(s, rng, m, True, False)


def nl_odd(s, rng, u):
    m = lu(u, 0.3, 15.0)
    ambient_column(s, rng)
    return m, "mg at 1 g", inj.nonlin_poly(s, rng, m, False, True)


def nl_mixed(s, rng, u):
    m = lu(u, 0.3, 15.0)
    ambient_column(s, rng)
    return m, "mg at 1 g", inj.nonlin_poly(s, rng, m, True, True)


def nl_saturation(s, rng, u):
    m = lu(u, 0.3, 15.0)
    ambient_column(s, rng)
    return m, "mg at 1 g", inj.nonlin_saturation(s, rng, m)


# settling ------------------------------------------------------------------------
def settle_exp(s, rng, u):
    m = lu(u, 0.5, 20.0)
    ambient_column(s, rng)
    return m, "mg initial", inj.settling_exponential(s, rng, m)


def settle_ring(s, rng, u):
    m = lu(u, 5.0, 200.0)
    ambient_column(s, rng)
    return m, "mg initial", inj.settling_ringing(s, rng, m)


def settle_both(s, rng, u):
    m = lu(u, 0.5, 20.0)
    ambient_column(s, rng)
    prm = inj.settling_exponential(s, rng, m)
    prm.update({"ring_" + k: v for k, v in inj.settling_ringing(s, rng, 10 * m).items()})
    return m, "mg initial (ringing 10x)", prm


# motion --------------------------------------------------------------------------
def motion_taps(s, rng, u):
    m = lu(u, 30.0, 1000.0)
    ambient_column(s, rng)
    return m, "mg peak", inj.motion_taps(s, rng, m)


def motion_sway(s, rng, u):
    m = lu(u, 0.01, 0.5)
    ambient_column(s, rng)
    return m, "deg rms tilt", inj.motion_sway(s, rng, m)


def motion_tremor(s, rng, u):
    m = lu(u, 2.0, 40.0)
    ambient_column(s, rng)
    return m, "mg rms per axis", inj.motion_tremor(s, rng, m)


# coloured noise ------------------------------------------------------------------
def cn_random_walk(s, rng, u):
    m = lu(u, 2.0, 100.0)
    ambient_column(s, rng)
    return m, "ug/sqrt(s)", inj.colored_random_walk(s, rng, m)


def cn_flicker(s, rng, u):
    m = lu(u, 10.0, 500.0)
    ambient_column(s, rng)
    return m, "ug (bias instability B)", inj.colored_flicker(s, rng, m)


def cn_gauss_markov(s, rng, u):
    m = lu(u, 20.0, 1000.0)
    ambient_column(s, rng)
    return m, "ug std", inj.colored_gauss_markov(s, rng, m)


def cn_flicker_rw(s, rng, u):
    m = lu(u, 10.0, 500.0)
    ambient_column(s, rng)
    prm = inj.colored_flicker(s, rng, m)
    k = m / 5.0
    inj.colored_random_walk(s, rng, k)
    prm["rw_ug_per_rts"] = round(k, 3)
    return m, "ug (B; K = B/5 per sqrt(s))", prm


# out of catalogue ----------------------------------------------------------------
def _ooc(fn, lo, hi, unit):
    def shape(s, rng, u):
        m = lu(u, lo, hi)
        ambient_column(s, rng)
        return m, unit, fn(s, rng, m)
    shape.__doc__ = fn.__doc__
    return shape


FAMILIES = {
    # family: (expected, {shape: fn})
    "clean": ("none", {
        "plain": clean_plain,
        "coarse-quant": clean_plain,   # part forced to adxl345 (3.9 mg/LSB) below
        "low-noise": clean_plain,      # part forced to adxl355 (25 ug/rtHz)
        "temp-inert": clean_temp_inert,
    }),
    "drift": ("drift", {
        "warmup": drift_warmup,
        "wander": drift_wander,
        "ramp": drift_ramp,
    }),
    "temperature": ("temperature", {
        "bias": temp_bias,
        "scale": temp_scale,
        "bias+scale": temp_bias_scale,
        "bias-lag": temp_bias_lag,
        "scale-lag": temp_scale_lag,
    }),
    "scale-nonlinearity": ("scale-nonlinearity", {
        "even": nl_even,
        "odd": nl_odd,
        "mixed": nl_mixed,
        "saturation": nl_saturation,
    }),
    "settling": ("settling", {
        "exponential": settle_exp,
        "ringing": settle_ring,
        "exp+ringing": settle_both,
    }),
    "motion": ("motion", {
        "taps": motion_taps,
        "sway": motion_sway,
        "tremor": motion_tremor,
    }),
    "colored-noise": ("colored-noise", {
        "random-walk": cn_random_walk,
        "flicker": cn_flicker,
        "gauss-markov": cn_gauss_markov,
        "flicker+rw": cn_flicker_rw,
    }),
    "out-of-catalogue": ("honest", {
        "bad-pose": _ooc(inj.ooc_bad_pose, 5.0, 150.0, "mg"),
        "mains": _ooc(inj.ooc_mains, 0.5, 20.0, "mg peak"),
        "hysteresis": _ooc(inj.ooc_hysteresis, 0.5, 10.0, "mg"),
        "cross-axis": _ooc(inj.ooc_cross_axis, 1.0, 20.0, "mg/g^2"),
        "g-step": _ooc(inj.ooc_g_step, 0.5, 10.0, "mg"),
        "single-step": _ooc(inj.ooc_single_step, 0.5, 10.0, "mg"),
    }),
}

FORCED_PART = {("clean", "coarse-quant"): "adxl345", ("clean", "low-noise"): "adxl355"}


def log_seed(seed, fam_idx, i):
    return int(np.random.SeedSequence([seed, fam_idx, i]).generate_state(1)[0])


def generate_one(out, family, shape, lseed, u, small, idx=0):
    """Build, inject, render and write one log; returns its manifest entry."""
    expected, shapes = FAMILIES[family]
    rng = np.random.default_rng(lseed)
    part = FORCED_PART.get((family, shape))
    s = Session(rng, small=small, part=part)
    magnitude, mag_unit, params = shapes[shape](s, rng, u)
    unit = str(rng.choice(UNITS))
    t, vals, header, fmt = render(s, unit, timestamp_jitter=bool(rng.random() < 0.5))
    name = f"{family}_{shape.replace('+', '-')}_{idx:03d}.csv"
    write_csv(os.path.join(out, name), t, vals, header, fmt, s.temp_log)
    return dict(file=name, family=family, shape=shape, seed=int(lseed), u=float(u),
                magnitude=round(magnitude, 5),
                magnitude_unit=mag_unit, unit=unit, expected=expected, part=s.part["name"],
                rate_hz=s.fs, poses=s.n_poses, hold_s=round(s.hold_nominal, 2),
                duration_s=round(s.duration, 1), rows=int(s.N), temp_column=s.temp_log is not None,
                white_noise_mg=round(s.white_sigma_g * 1e3, 4), small=small,
                params={k: v for k, v in params.items()},
                hold_rows=[[int(a), int(b)] for a, b in s.holds])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--per-family", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--small", action="store_true", help="12-16 poses at 100 Hz, 3-8 s holds")
    ap.add_argument("--families", default=",".join(FAMILIES), help="comma list (default: all)")
    ap.add_argument("--replay", metavar="MANIFEST", help="regenerate the logs of a manifest.json into --out "
                    "(all, or those named by --files)")
    ap.add_argument("--files", default="", help="with --replay: comma list of file names")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    if a.replay:
        with open(a.replay) as fh:
            old = json.load(fh)
        want = set(f for f in a.files.split(",") if f)
        again = []
        for idx, e in enumerate(old):
            if want and e["file"] not in want:
                continue
            m = generate_one(a.out, e["family"], e["shape"], e["seed"], e["u"], e.get("small", False),
                             int(e["file"].rsplit("_", 1)[1].split(".")[0]))
            again.append(m)
        with open(os.path.join(a.out, "manifest.json"), "w") as fh:
            json.dump(again, fh, indent=1)
        print(f"{len(again)} logs replayed into {a.out}")
        return
    fams = [f for f in a.families.split(",") if f]
    for f in fams:
        if f not in FAMILIES:
            ap.error(f"unknown family {f!r}; known: {', '.join(FAMILIES)}")
    manifest = []
    t0 = time.time()
    for fam in fams:
        fi = list(FAMILIES).index(fam)
        shapes = list(FAMILIES[fam][1])
        for i in range(a.per_family):
            shape = shapes[i % len(shapes)]
            # sweep magnitudes: the j-th log of a shape sits at a stratified random point
            rounds = max(1, math.ceil(a.per_family / len(shapes)))
            j = i // len(shapes)
            lseed = log_seed(a.seed, fi, i)
            u = (j + np.random.default_rng(lseed ^ 0x5EED).random()) / rounds
            manifest.append(generate_one(a.out, fam, shape, lseed, u, a.small, i))
            m = manifest[-1]
            print(f"{m['file']}: {m['part']} {m['rate_hz']:g} Hz {m['poses']} poses {m['rows']} rows "
                  f"{m['unit']} magnitude {m['magnitude']:.4g} {m['magnitude_unit']}", file=sys.stderr)
    with open(os.path.join(a.out, "manifest.json"), "w") as fh:
        json.dump(manifest, fh, indent=1)
    print(f"{len(manifest)} logs in {a.out} ({time.time() - t0:.1f} s)")


if __name__ == "__main__":
    main()
